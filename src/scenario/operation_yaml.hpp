// The `operations:` entries of a scenario: function, unit, address range or reference numbers,
// quantity within the function's limit, address distribution, write values, `expect` checks
// and per-operation thresholds.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "codec/limits.hpp"
#include "codec/values.hpp"
#include "load/plan.hpp"
#include "scenario/expect.hpp"
#include "scenario/threshold.hpp"
#include "scenario/yaml_reader.hpp"

namespace mbstorm::scenario {

struct ParsedOperation {
    load::Operation operation;
    Expectation expect;
    std::vector<ThresholdSpec> thresholds;  // operation name filled in
    bool named = false;                     // `name:` given
};

ParsedOperation parse_operation(const YamlReader& reader, const YAML::Node& node,
                                std::size_t index);

// The table a function's addresses refer to; nullopt when it takes no address.
std::optional<codec::Table> function_table(std::uint8_t function) noexcept;
// Quantity range of the function (max 0: the function takes no quantity); the codec owns it.
using QuantityLimits = codec::limits::QuantityRange;
QuantityLimits quantity_limits(std::uint8_t function) noexcept;
// Functions whose requests carry data the `values` generator fills.
bool takes_values(std::uint8_t function) noexcept;

}  // namespace mbstorm::scenario
