// Typed reads of YAML nodes for every YAML document mbstorm reads (device descriptions and
// scenarios). Errors name the place as "<source>:<line>:<column>: <what>" and the valid keys or
// range; each caller raises them as its own exception type. Not on any hot path.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <functional>
#include <initializer_list>
#include <span>
#include <string>
#include <string_view>

namespace mbstorm::yaml {

// Throws the caller's error type; must not return. `line` and `column` are 1-based, 0 unknown.
using RaiseError = void (*)(const std::string& message, int line, int column);

class Reader {
  public:
    Reader(std::string source, RaiseError raise) : source_(std::move(source)), raise_(raise) {}
    const std::string& source() const noexcept { return source_; }

    [[noreturn]] void fail(const YAML::Mark& mark, const std::string& message) const;
    [[noreturn]] void fail(const YAML::Node& node, const std::string& message) const {
        fail(node.Mark(), message);
    }
    std::string where(const YAML::Node& node) const;  // "file:line:column"

    using KeyVisitor =
        std::function<void(const std::string& key, const YAML::Node& key_node, const YAML::Node&)>;
    // Calls f(key, key node, value) for each entry of a mapping; unknown keys (not in `known`)
    // and duplicates fail, naming the valid keys.
    void each_key(const YAML::Node& map, std::string_view what,
                  std::span<const std::string_view> known, const KeyVisitor& f) const;
    void each_key(const YAML::Node& map, std::string_view what,
                  std::initializer_list<std::string_view> known, const KeyVisitor& f) const {
        each_key(map, what, std::span<const std::string_view>(known.begin(), known.size()), f);
    }

    std::string scalar(const YAML::Node& n, std::string_view what) const;
    // Decimal, 0x hex or 0b binary, optionally signed; must lie in [lo, hi].
    std::int64_t integer(const YAML::Node& n, std::string_view what, std::int64_t lo,
                         std::int64_t hi) const;
    // A finite number (integer forms as above, or decimal with fraction and exponent).
    double number(const YAML::Node& n, std::string_view what) const;
    double number(const YAML::Node& n, std::string_view what, double lo, double hi) const;
    // true/yes/on or false/no/off, in any case.
    bool boolean(const YAML::Node& n, std::string_view what) const;
    // One of `choices`.
    std::string choice(const YAML::Node& n, std::string_view what,
                       std::initializer_list<std::string_view> choices) const;

    // The integer forms of integer(), without a range; false when `s` is not one.
    static bool parse_integer(std::string_view s, std::int64_t& out);

  private:
    std::string source_;
    RaiseError raise_;
};

}  // namespace mbstorm::yaml
