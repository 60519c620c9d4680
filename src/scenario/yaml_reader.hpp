// Typed reads of YAML nodes that fail with "<source>:<line>:<column>: <what>" and the valid
// range. Shared by the scenario parser's pieces; not on any hot path (throws ScenarioError).
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <functional>
#include <initializer_list>
#include <string>
#include <string_view>

#include "load/plan.hpp"

namespace mbstorm::scenario {

// A node that may not have been given. (A default YAML::Node is a defined null node, and
// assigning to a YAML::Node that already refers to a document node rewrites that node, so
// optional keys are held here instead.)
struct NodeSlot {
    YAML::Node node;
    bool set = false;
    NodeSlot& operator=(const YAML::Node& n) {
        node.reset(n);
        set = true;
        return *this;
    }
    explicit operator bool() const noexcept { return set; }
    operator const YAML::Node&() const noexcept { return node; }  // NOLINT: implicit on purpose
};

class YamlReader {
  public:
    explicit YamlReader(std::string source) : source_(std::move(source)) {}
    const std::string& source() const noexcept { return source_; }

    [[noreturn]] void fail(const YAML::Mark& mark, const std::string& message) const;
    [[noreturn]] void fail(const YAML::Node& node, const std::string& message) const {
        fail(node.Mark(), message);
    }
    std::string where(const YAML::Node& node) const;  // "file:line:column"

    // Calls f(key, key node, value) for each entry; unknown keys (not in `known`) and
    // duplicates fail, naming the valid keys.
    void each_key(
        const YAML::Node& map, std::string_view what, std::initializer_list<std::string_view> known,
        const std::function<void(const std::string&, const YAML::Node&, const YAML::Node&)>& f)
        const;

    std::string scalar(const YAML::Node& n, std::string_view what) const;
    // Decimal or 0x hex; must lie in [lo, hi].
    std::int64_t integer(const YAML::Node& n, std::string_view what, std::int64_t lo,
                         std::int64_t hi) const;
    double number(const YAML::Node& n, std::string_view what, double lo, double hi) const;
    bool boolean(const YAML::Node& n, std::string_view what) const;
    // "500ms", "10s", "2m"; a bare number is seconds. Must lie in [lo, hi] (hi 0: no limit).
    load::Duration duration(const YAML::Node& n, std::string_view what, load::Duration lo,
                            load::Duration hi, bool lo_exclusive = false) const;
    // One of `choices`.
    std::string choice(const YAML::Node& n, std::string_view what,
                       std::initializer_list<std::string_view> choices) const;

    static bool parse_integer(std::string_view s, std::int64_t& out);

  private:
    std::string source_;
};

// "10s", "250ms", "1.5s" — the shortest exact text for a duration (re-parses to the same).
std::string duration_text(load::Duration d);

}  // namespace mbstorm::scenario
