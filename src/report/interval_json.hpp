// One timeline interval as JSON: the object of --json's timeline.intervals[] and of each
// --timeline line (keys: docs/json-schema.md).
#pragma once

#include <nlohmann/json.hpp>

#include "stats/interval_recorder.hpp"

namespace mbstorm::report {

nlohmann::json interval_json(const stats::IntervalSummary& interval);

}  // namespace mbstorm::report
