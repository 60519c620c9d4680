// Thresholds as JUnit XML (one test case each), so CI systems show them natively.
#pragma once

#include <string>

#include "stats/run_result.hpp"

namespace mbstorm::report {

// `run_error`: non-empty when the run itself failed; it becomes one more failing test case.
std::string format_junit(const stats::RunResult& run, const std::string& suite_name,
                         const std::string& run_error = {});

}  // namespace mbstorm::report
