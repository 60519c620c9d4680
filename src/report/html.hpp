// One self-contained HTML page: inline CSS and inline SVG only, no scripts, no external
// fetches. Latency-by-percentile plot (HdrHistogram style, log x axis on 1/(1-p)),
// throughput and latency over time (stage boundaries marked), summary and error tables.
#pragma once

#include <string>

#include "stats/run_result.hpp"

namespace mbstorm::report {

std::string format_html(const stats::RunResult& result);

}  // namespace mbstorm::report
