#include "scenario/yaml_reader.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <set>

#include "stats/duration_text.hpp"

namespace mbstorm::scenario {

namespace {

[[noreturn]] void raise_scenario_error(const std::string& message, int line, int column) {
    throw ScenarioError(message, line, column);
}

}  // namespace

YamlReader::YamlReader(std::string source)
    : yaml::Reader(std::move(source), &raise_scenario_error) {}

load::Duration YamlReader::duration(const YAML::Node& n, std::string_view what, load::Duration lo,
                                    load::Duration hi, bool lo_exclusive) const {
    const std::string s = scalar(n, what);
    const std::string range =
        hi.count() > 0 ? fmt::format("valid {}{}..{}", lo_exclusive ? "> " : "", duration_text(lo),
                                     duration_text(hi))
                       : fmt::format("valid {} {}", lo_exclusive ? ">" : ">=", duration_text(lo));
    std::uint64_t ns = 0;
    if (!stats::parse_duration_ns(s, ns) || ns > static_cast<std::uint64_t>(INT64_MAX)) {
        fail(n, fmt::format("{}: '{}' is not a duration (e.g. 500ms, 10s, 1m30s; a bare number is "
                            "seconds; {})",
                            what, s, range));
    }
    const load::Duration d{static_cast<std::int64_t>(ns)};
    if (d < lo || (lo_exclusive && d == lo) || (hi.count() > 0 && d > hi)) {
        fail(n, fmt::format("{}: {} is out of range ({})", what, s, range));
    }
    return d;
}

std::string duration_text(load::Duration d) {
    const std::int64_t ns = d.count();
    if (ns == 0) return "0s";
    if (ns % 3'600'000'000'000 == 0) return fmt::format("{}h", ns / 3'600'000'000'000);
    if (ns % 60'000'000'000 == 0) return fmt::format("{}m", ns / 60'000'000'000);
    if (ns % 1'000'000'000 == 0) return fmt::format("{}s", ns / 1'000'000'000);
    if (ns % 1'000'000 == 0) return fmt::format("{}ms", ns / 1'000'000);
    if (ns % 1'000 == 0) return fmt::format("{}us", ns / 1'000);
    return fmt::format("{}ns", ns);
}

}  // namespace mbstorm::scenario
