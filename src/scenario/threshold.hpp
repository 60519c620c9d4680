// Threshold expressions over a run's results, e.g. "p99 < 5ms", "error_rate < 0.1%",
// "throughput > 50000/s", "exceptions[02] == 0"; overall or for one operation.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "stats/run_result.hpp"
#include "util/error.hpp"

namespace mbstorm::scenario {

enum class Metric : std::uint8_t {
    Percentile,    // latency at `percentile`
    Min,           // latency
    Max,           // latency
    Mean,          // latency
    ErrorRate,     // errors / completed, a fraction
    Errors,        // count
    Throughput,    // completed transactions per second over the measured time
    Transactions,  // completed count
    Exceptions,    // count of exception responses (all codes, or `exception_code`)
    Timeouts,      // count
    Mismatches,    // count of `expect` failures
};

enum class Comparison : std::uint8_t { Less, LessEqual, Greater, GreaterEqual, Equal, NotEqual };

struct ThresholdSpec {
    std::string text;       // as written, normalised ("p99 < 5ms")
    std::string operation;  // empty: the whole run
    Metric metric = Metric::Percentile;
    double percentile = 99.0;
    int exception_code = -1;  // Metric::Exceptions: -1 = all codes
    Comparison comparison = Comparison::Less;
    double limit = 0;  // ns for latencies, a fraction for rates, per second, or a count
    // Where a scenario wrote it: under its operation's `thresholds:` (true), or in the top-level
    // list (false; `{operation: NAME, check: ...}` when it names one). The printer writes it
    // back there, so a printed scenario reads back in the same order and within the same caps.
    bool in_operation = false;
    bool operator==(const ThresholdSpec&) const = default;
};

// Parses an expression; an InvalidInput error naming the accepted forms.
Result<ThresholdSpec> parse_threshold(std::string_view text);

// Evaluates against the run (the operation is looked up by name in run.operations).
stats::ThresholdResult evaluate_threshold(const ThresholdSpec& spec, const stats::RunResult& run);

// "5ms", "0.1%", "50000/s", "3" for the metric's unit.
std::string format_metric_value(Metric metric, double value);

}  // namespace mbstorm::scenario
