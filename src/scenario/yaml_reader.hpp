// The scenario parser's YAML reader: the shared one (yaml/reader.hpp) throwing ScenarioError,
// with durations added. Not on any hot path. The exception stays inside the scenario layer:
// parse_scenario catches it and returns an Error (scenario.hpp).
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <string>
#include <string_view>

#include "load/plan.hpp"
#include "yaml/positioned_error.hpp"
#include "yaml/reader.hpp"

namespace mbstorm::scenario {

// What the reader throws from deep inside a document; never leaves the scenario layer.
class ScenarioError : public yaml::PositionedError {
  public:
    using PositionedError::PositionedError;
};

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

// The shared YAML reader (yaml/reader.hpp) raising ScenarioError, plus durations.
class YamlReader : public yaml::Reader {
  public:
    explicit YamlReader(std::string source);

    // "500ms", "10s", "2m"; a bare number is seconds. Must lie in [lo, hi] (hi 0: no limit).
    load::Duration duration(const YAML::Node& n, std::string_view what, load::Duration lo,
                            load::Duration hi, bool lo_exclusive = false) const;
};

// "10s", "250ms", "1.5s" — the shortest exact text for a duration (re-parses to the same).
std::string duration_text(load::Duration d);

}  // namespace mbstorm::scenario
