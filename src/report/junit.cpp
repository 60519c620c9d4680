#include "report/junit.hpp"
#include "report/xml_escape.hpp"

#include <fmt/format.h>

namespace mbstorm::report {

std::string format_junit(const stats::RunResult& run, const std::string& suite_name,
                         const std::string& run_error) {
    std::size_t failures = 0;
    for (const auto& t : run.thresholds) failures += t.passed ? 0 : 1;
    const std::size_t tests = run.thresholds.size() + (run_error.empty() ? 0 : 1);
    failures += run_error.empty() ? 0 : 1;
    const double seconds = static_cast<double>(run.metadata.measured_duration_ns) / 1e9;
    const std::string suite = xml_escape(suite_name);
    std::string out = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
    out +=
        fmt::format("<testsuites name=\"mbstorm\" tests=\"{}\" failures=\"{}\" time=\"{:.3f}\">\n",
                    tests, failures, seconds);
    out += fmt::format(
        "  <testsuite name=\"{}\" tests=\"{}\" failures=\"{}\" errors=\"0\" "
        "skipped=\"0\" time=\"{:.3f}\">\n",
        suite, tests, failures, seconds);
    if (!run_error.empty()) {
        out += fmt::format(
            "    <testcase classname=\"mbstorm.{}\" name=\"run completed\" time=\"{:.3f}\">\n"
            "      <failure message=\"{}\" type=\"run\"/>\n    </testcase>\n",
            suite, seconds, xml_escape(run_error));
    }
    for (const auto& t : run.thresholds) {
        const std::string observed =
            t.observed_text.empty() ? fmt::format("{}", t.observed) : t.observed_text;
        out += fmt::format("    <testcase classname=\"mbstorm.{}\" name=\"{}\" time=\"0\">\n",
                           suite, xml_escape(t.expression));
        if (t.passed) {
            out +=
                fmt::format("      <system-out>observed {}</system-out>\n", xml_escape(observed));
        } else {
            out += fmt::format(
                "      <failure message=\"threshold breached: observed {}\" "
                "type=\"threshold\">{} (observed {})</failure>\n",
                xml_escape(observed), xml_escape(t.expression), xml_escape(observed));
        }
        out += "    </testcase>\n";
    }
    out += "  </testsuite>\n</testsuites>\n";
    return out;
}

}  // namespace mbstorm::report
