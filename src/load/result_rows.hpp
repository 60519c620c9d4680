// The empty result rows a load worker (io_uring or serial) fills: one per plan operation, and
// one per stage with, for mixes, a row per operation inside it.
#pragma once

#include <cstddef>
#include <vector>

#include "load/plan.hpp"
#include "stats/run_result.hpp"

namespace mbstorm::load {

std::vector<stats::OperationResult> operation_rows(const std::vector<Operation>& operations);

// A one-operation mix would repeat every stage row: per-stage operations only for mixes.
std::vector<stats::StageResult> stage_rows(std::size_t stages,
                                           const std::vector<stats::OperationResult>& operations);

}  // namespace mbstorm::load
