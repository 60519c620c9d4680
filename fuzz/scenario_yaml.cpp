// libFuzzer harness: scenario YAML (the user's file, and the thresholds `merge` reads back) ->
// a validated Scenario, or a ScenarioError naming the position. A scenario it accepts prints
// (run --print-scenario) as YAML that parses to a scenario printing the same. Any other
// exception, or a sanitizer report, is a bug.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "scenario/print.hpp"
#include "scenario/scenario.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace mbstorm::scenario;
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    Scenario s;
    try {
        s = parse_scenario(text);
    } catch (const ScenarioError&) {
        return 0;
    }
    const std::string printed = format_scenario(s);
    try {
        if (format_scenario(parse_scenario(printed)) != printed) std::abort();
    } catch (const ScenarioError&) {
        std::abort();  // what it printed, it must read back
    }
    return 0;
}
