// Runs a scenario: starts the embedded reference slave when there is no target, runs the
// engine (once, or once per stage step for staged runs), merges the results into one RunResult
// with per-stage breakdown, and evaluates the thresholds.
#pragma once

#include <atomic>
#include <functional>
#include <string>
#include <vector>

#include "load/engine.hpp"
#include "scenario/scenario.hpp"

namespace mbstorm::scenario {

struct RunHooks {
    const std::atomic<bool>* stop = nullptr;
    load::ProgressCallback on_progress;
    std::function<void(const std::string&)> on_message;  // e.g. "embedded slave on ..."
    std::string tool_version = "mbstorm";
};

// One engine run of a staged schedule: a stage, or a slice of a linear ramp.
struct StageStep {
    std::size_t stage = 0;
    load::Duration duration{};
    double rate = 0;                // open loop
    std::uint32_t connections = 0;  // 0 (or rate 0 in open loop): an idle step, no traffic
};

// The schedule as engine runs. Linear ramps become steps of at most `stage_step`, each at the
// ramp's value at the step's midpoint; a stage whose values do not change is a single step.
std::vector<StageStep> plan_stage_steps(const Scenario& scenario);

// The result; result.ok false with result.error when nothing could be run.
load::LoadResult run_scenario(const Scenario& scenario, const RunHooks& hooks = {});

// Merges one engine run into `total` (offsets shifted by what was measured before) and into
// `stage`. Exposed for tests.
void merge_step(stats::RunResult& total, const stats::RunResult& step, stats::StageResult* stage);

// Thresholds of the scenario evaluated against `run` (fills run.thresholds).
void evaluate_thresholds(const Scenario& scenario, stats::RunResult& run);

}  // namespace mbstorm::scenario
