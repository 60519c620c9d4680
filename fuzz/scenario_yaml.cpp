// libFuzzer harness: scenario YAML (the user's file, and the thresholds `merge` reads back) ->
// a validated Scenario, or an Error naming the position. A scenario it accepts prints
// (run --print-scenario) as YAML that parses back to the same scenario, compared member by
// member: the load plan, the stages, thresholds, read-back checks and the embedded slave (not
// only the printed text, which a printer that drops a field would still reproduce). Any other
// exception, or a sanitizer report, is a bug.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>

#include "scenario/print.hpp"
#include "scenario/scenario.hpp"

namespace {

using mbstorm::scenario::Scenario;

// The first member the two scenarios differ in, or nullptr. Not compared: `source` (the
// file name, for messages), `model` (whether `model:` was written: the printer always writes
// it; plan.model, the model that runs, is compared) and `slave_given` (the printer writes the
// slave section whenever there is no target).
const char* first_difference(const Scenario& a, const Scenario& b) {
    const mbstorm::load::Plan& p = a.plan;
    const mbstorm::load::Plan& q = b.plan;
    if (a.name != b.name) return "name";
    if (a.description != b.description) return "description";
    if (a.target != b.target) return "target";
    if (p.operations != q.operations) return "plan.operations";
    if (p.stages != q.stages) return "plan.stages";
    if (p.model != q.model || p.rate != q.rate || p.arrival != q.arrival) return "plan model";
    if (p != q) return "plan";
    if (a.stages != b.stages) return "stages";
    if (a.thresholds != b.thresholds) return "thresholds";
    if (a.expectations != b.expectations) return "expectations";
    if (a.slave != b.slave) return "slave";
    if (a.slave_threads != b.slave_threads) return "slave_threads";
    if (a.total_duration() != b.total_duration()) return "total_duration";
    return nullptr;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace mbstorm::scenario;
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    const auto parsed = parse_scenario(text);
    if (!parsed.ok()) return 0;
    const Scenario& s = *parsed;
    const std::string printed = format_scenario(s);
    const auto reread = parse_scenario(printed);
    if (!reread.ok()) {
        std::fprintf(stderr, "printed scenario does not read back: %s\n%s",
                     reread.error().text().c_str(), printed.c_str());
        std::abort();  // what it printed, it must read back
    }
    const Scenario& again = *reread;
    if (const char* what = first_difference(s, again)) {
        std::fprintf(stderr, "printed and read back, the scenario's %s changed:\n%s", what,
                     printed.c_str());
        std::abort();
    }
    if (format_scenario(again) != printed) std::abort();
    return 0;
}
