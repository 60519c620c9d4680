// `mbstorm run --print-scenario`: the fully resolved scenario as YAML, every default written
// out, in a form parse_scenario() reads back to the same scenario.
#pragma once

#include <string>

#include "scenario/scenario.hpp"

namespace mbstorm::scenario {

std::string format_scenario(const Scenario& scenario);

// How a scenario names an address mode (its `distribution`: sequential, uniform, zipf).
const char* address_mode_name(load::AddressMode m);

}  // namespace mbstorm::scenario
