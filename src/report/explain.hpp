// Plain-language verdicts shared by the console, HTML and JSON reports, so that each says the
// same thing in the same words: the load schedule as planned, why sends were late, what the
// plan asked for and did not get, and hints the user can act on.
#pragma once

#include <string>
#include <vector>

#include "stats/run_result.hpp"

namespace mbstorm::report {

// The open-loop rates a run went through, in order, repeats folded: {8000} for a flat run,
// {500, 8000} for a ramp from 500 to 8,000/s. Empty in a closed loop.
std::vector<double> rate_schedule(const stats::RunResult& r);

// "closed loop", "open loop, 8.00k req/s" or "open loop, stages 500 → 8.00k req/s".
std::string load_model_text(const stats::RunResult& r);

// A stage's target rate: "8.00k" when it holds, "500 → 8.00k" when it ramps; "-" in a closed
// loop.
std::string stage_rate_text(const stats::StageResult& stage, stats::LoadModel model);

// Open loop: whether sends kept their schedule, and when not, whether the engine or the target
// was the cause ("kept (no late sends)", "engine fell behind: ...", "target not keeping up:
// ..."). Empty in a closed loop.
std::vector<std::string> schedule_lines(const stats::RunResult& r);

// "none", "engine", "target" or "engine_and_target".
const char* schedule_lag_cause(const stats::ScheduleLag& lag);

// Things the user can change, e.g. "use --depth 1" for a target that does not pipeline.
std::vector<std::string> hint_lines(const stats::RunResult& r);

}  // namespace mbstorm::report
