// The scenario layer returns Result<Scenario>; most tests want the scenario and fail loudly
// when there is none. An exception here (in a test, not in src/) lets EXPECT_NO_THROW and
// GoogleTest's "C++ exception thrown" name the refusal.
#pragma once

#include <stdexcept>
#include <string>
#include <string_view>

#include "scenario/scenario.hpp"

namespace mbstorm::scenario {

inline Scenario must_parse(std::string_view text, std::string_view source = "<scenario>") {
    Result<Scenario> parsed = parse_scenario(text, source);
    if (!parsed.ok()) throw std::runtime_error("refused: " + parsed.error().text());
    return std::move(parsed).value();
}

inline Scenario must_load(const std::string& path) {
    Result<Scenario> loaded = load_scenario_file(path);
    if (!loaded.ok()) throw std::runtime_error("refused: " + loaded.error().text());
    return std::move(loaded).value();
}

}  // namespace mbstorm::scenario
