// libFuzzer harness: scenario YAML (the user's file, and the thresholds `merge` reads back) ->
// a validated Scenario, or a ScenarioError naming the position. Any other exception, or a
// sanitizer report, is a bug.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "scenario/scenario.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    try {
        const mbstorm::scenario::Scenario s = mbstorm::scenario::parse_scenario(text);
        (void)s.total_duration();
    } catch (const mbstorm::scenario::ScenarioError&) {
    }
    return 0;
}
