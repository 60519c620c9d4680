// Operation names in a scenario: explicit names must be unique; a default name (the
// function's) gets a suffix _2, _3, ... when taken. Linear in the number of operations: the
// search for a free suffix resumes where the last one for the same default name stopped
// (it used to start at _2 every time, quadratic for many unnamed operations of one function).
#pragma once

#include <cstddef>
#include <set>
#include <string>
#include <unordered_map>

namespace mbstorm::scenario {

class OperationNames {
  public:
    // False when the name is already taken.
    bool add_explicit(const std::string& name) { return names_.insert(name).second; }
    // Registers and returns `base`, or `base_K` with the smallest free K >= 2 not tried before.
    std::string add_default(const std::string& base);
    bool contains(const std::string& name) const { return names_.count(name) != 0; }
    const std::set<std::string>& all() const noexcept { return names_; }
    // Names tried by add_default so far (the tests check it grows linearly).
    std::size_t probes() const noexcept { return probes_; }

  private:
    std::set<std::string> names_;
    std::unordered_map<std::string, int> next_suffix_;  // by default name
    std::size_t probes_ = 0;
};

}  // namespace mbstorm::scenario
