// Machine-readable run summary (`--json`). Schema: docs/json-schema.md.
#pragma once

#include <string>

#include "stats/run_result.hpp"

namespace mbstorm::report {

inline constexpr int kJsonSchemaVersion = 1;

// indent < 0: compact single line.
std::string format_json(const stats::RunResult& result, int indent = 2);

}  // namespace mbstorm::report
