// Runs a scenario: starts the embedded reference slave when there is no target, runs the
// engine once (stages included), and evaluates the thresholds.
#pragma once

#include <atomic>
#include <chrono>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "load/engine.hpp"
#include "load/shard.hpp"
#include "scenario/scenario.hpp"

namespace mbstorm::scenario {

struct RunHooks {
    const std::atomic<bool>* stop = nullptr;
    load::ProgressCallback on_progress;
    std::function<void(const std::string&)> on_message;  // e.g. "embedded slave on ..."
    std::string tool_version = "mbstorm";
    load::IntervalHistogramsCallback on_interval_histograms;  // --hlog
    load::LiveMetrics* live = nullptr;                        // --metrics-listen
    load::IntervalCallback on_interval;                       // --timeline
    load::Plan::Shard shard;                                  // run --shard: count 0 = whole plan
    std::optional<std::chrono::system_clock::time_point> start_at;  // run --start-at
    net::BackendChoice backend = net::BackendChoice::Auto;          // run --backend
};

// The engine's plan for the scenario (its stages included; host and port as in the file),
// or a shard's part of it (load/shard.hpp; an InvalidInput error says why a shard has none).
load::Plan engine_plan(const Scenario& scenario);
Result<load::Plan> engine_plan(const Scenario& scenario, load::Plan::Shard shard);

// The result; result.error says why when nothing could be run or the run ended early.
load::LoadResult run_scenario(const Scenario& scenario, const RunHooks& hooks = {});

// Thresholds of the scenario evaluated against `run` (fills run.thresholds).
void evaluate_thresholds(const Scenario& scenario, stats::RunResult& run);

}  // namespace mbstorm::scenario
