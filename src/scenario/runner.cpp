// Staged runs: until the engine ramps by itself, each stage (or each slice of a linear ramp)
// is one engine run, and the results are merged into one RunResult with a StageResult per
// stage. Connections are re-opened at every step boundary; steps of 1 s keep that cost small.
#include "scenario/runner.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <thread>

#include "scenario/expect.hpp"
#include "server/server.hpp"
#include "slave/device_yaml.hpp"

namespace mbstorm::scenario {
namespace {

void add_operation(std::vector<stats::OperationResult>& into, std::size_t index,
                   const stats::OperationResult& from) {
    if (into.size() <= index) into.resize(index + 1);
    stats::OperationResult& op = into[index];
    if (op.name.empty()) {
        op.name = from.name;
        op.function_code = from.function_code;
    }
    op.latency.add(from.latency);
    op.counters.add(from.counters);
}

bool is_idle(const load::Plan& plan, const StageStep& step) {
    return step.connections == 0 || (plan.model == load::LoadModel::OpenLoop && step.rate <= 0);
}

// Sleeps `d` unless stopped; true when it slept the whole time.
bool idle_for(load::Duration d, const std::atomic<bool>* stop) {
    const auto end = std::chrono::steady_clock::now() + d;
    while (std::chrono::steady_clock::now() < end) {
        if (stop != nullptr && stop->load()) return false;
        std::this_thread::sleep_for(std::min<std::chrono::nanoseconds>(
            std::chrono::milliseconds(20), end - std::chrono::steady_clock::now()));
    }
    return true;
}

}  // namespace

std::vector<StageStep> plan_stage_steps(const Scenario& s) {
    std::vector<StageStep> steps;
    double prev_rate = s.plan.rate;
    double prev_connections = s.plan.connections;
    const std::int64_t step_ns = std::max<std::int64_t>(s.stage_step.count(), 1'000'000);
    for (std::size_t i = 0; i < s.stages.size(); ++i) {
        const StageSpec& st = s.stages[i];
        const double end_rate = st.rate.value_or(prev_rate);
        const double end_connections =
            st.connections ? static_cast<double>(*st.connections) : prev_connections;
        const bool flat = end_rate == prev_rate && end_connections == prev_connections;
        if (st.ramp == load::Ramp::Constant || flat) {
            steps.push_back(
                {i, st.duration, end_rate, static_cast<std::uint32_t>(end_connections)});
        } else {
            const std::int64_t total = st.duration.count();
            for (std::int64_t t0 = 0; t0 < total; t0 += step_ns) {
                const std::int64_t d = std::min(step_ns, total - t0);
                const double at = (static_cast<double>(t0) + static_cast<double>(d) / 2.0) /
                                  static_cast<double>(total);
                StageStep step;
                step.stage = i;
                step.duration = load::Duration(d);
                step.rate = prev_rate + (end_rate - prev_rate) * at;
                step.connections = static_cast<std::uint32_t>(
                    std::llround(prev_connections + (end_connections - prev_connections) * at));
                steps.push_back(step);
            }
        }
        prev_rate = end_rate;
        prev_connections = end_connections;
    }
    return steps;
}

void merge_step(stats::RunResult& total, const stats::RunResult& step, stats::StageResult* stage) {
    const std::uint64_t offset = total.metadata.measured_duration_ns;
    // A one-operation mix would repeat every stage row; list operations per stage only for mixes.
    const bool per_stage_operations = stage != nullptr && step.operations.size() > 1;
    for (std::size_t i = 0; i < step.operations.size(); ++i) {
        add_operation(total.operations, i, step.operations[i]);
        if (per_stage_operations) add_operation(stage->operations, i, step.operations[i]);
    }
    total.latency.add(step.latency);
    total.counters.add(step.counters);
    if (stage != nullptr) {
        stage->latency.add(step.latency);
        stage->counters.add(step.counters);
    }
    total.timeline_interval_ns = step.timeline_interval_ns;
    for (std::size_t i = 0; i < step.timeline.size(); ++i) {
        stats::IntervalSummary iv = step.timeline[i];
        if (i + 1 == step.timeline.size()) {
            // The step's last interval covers only what was measured of it.
            const std::uint64_t measured = step.metadata.measured_duration_ns;
            const std::uint64_t covered =
                measured > iv.start_offset_ns ? measured - iv.start_offset_ns : 0;
            // A sliver at the end of a step would plot as a false dip: fold it into the interval
            // before (counts add; the percentiles stay those of the full interval).
            if (i > 0 && covered < iv.duration_ns / 2) {
                stats::IntervalSummary& prev = total.timeline.back();
                prev.transactions += iv.transactions;
                prev.errors += iv.errors;
                prev.latency_count += iv.latency_count;
                prev.max_ns = std::max(prev.max_ns, iv.max_ns);
                prev.duration_ns += covered;
                break;
            }
            if (covered > 0) iv.duration_ns = std::min(iv.duration_ns, covered);
        }
        iv.index = total.timeline.size();
        iv.start_offset_ns += offset;
        total.timeline.push_back(iv);
    }
    total.schedule_lag.late_sends += step.schedule_lag.late_sends;
    total.schedule_lag.total_lag_ns += step.schedule_lag.total_lag_ns;
    total.schedule_lag.max_lag_ns =
        std::max(total.schedule_lag.max_lag_ns, step.schedule_lag.max_lag_ns);
    total.connections.opened += step.connections.opened;
    total.connections.failed += step.connections.failed;
    total.connections.reconnects += step.connections.reconnects;
    total.connections.closed_by_peer += step.connections.closed_by_peer;
    total.metadata.measured_duration_ns += step.metadata.measured_duration_ns;
}

void evaluate_thresholds(const Scenario& s, stats::RunResult& run) {
    run.thresholds.clear();
    for (const auto& spec : s.thresholds) run.thresholds.push_back(evaluate_threshold(spec, run));
}

load::LoadResult run_scenario(const Scenario& s, const RunHooks& hooks) {
    load::LoadResult out;
    load::Plan plan = s.plan;
    plan.stages.clear();
    auto say = [&hooks](const std::string& m) {
        if (hooks.on_message) hooks.on_message(m);
    };

    // The embedded slave's models must outlive the server: declared first, destroyed last.
    std::unique_ptr<slave::UnitModels> units;
    std::unique_ptr<server::Server> embedded;
    if (s.target.empty()) {
        const unsigned cores = std::max(1U, std::thread::hardware_concurrency());
        units = std::make_unique<slave::UnitModels>(slave::build_units(s.slave));
        server::ServerConfig sc;
        sc.listen = "127.0.0.1:0";
        // Split the cores between the engine and the slave unless told otherwise.
        sc.threads = s.slave_threads != 0 ? s.slave_threads : std::max(1U, cores / 2);
        if (plan.threads == 0) plan.threads = std::max(1U, cores - std::min(cores - 1, sc.threads));
        sc.max_connections = 0;
        sc.faults = s.slave.faults;
        sc.units = units.get();
        sc.simulated = s.slave.simulated;
        embedded = std::make_unique<server::Server>(sc);
        std::string error;
        if (!embedded->start(&error)) {
            out.error = "cannot start the embedded reference slave: " + error;
            return out;
        }
        plan.host = "127.0.0.1";
        plan.port = embedded->port();
        say(fmt::format("no target: load-testing the embedded reference slave on {} ({} thread{})",
                        embedded->endpoint(), embedded->threads(),
                        embedded->threads() == 1 ? "" : "s"));
    } else {
        std::string error;
        if (!parse_target(s.target, plan.host, plan.port, error)) {
            out.error = "target: " + error;
            return out;
        }
    }

    load::EngineOptions eo;
    eo.stop = hooks.stop;
    eo.tool_version = hooks.tool_version;
    eo.verifier = make_verifier(s.expectations);

    if (s.stages.empty()) {
        eo.on_progress = hooks.on_progress;
        out = load::run_load(plan, eo);
    } else {
        const std::vector<StageStep> steps = plan_stage_steps(s);
        stats::RunResult total;
        total.stages.resize(s.stages.size());
        for (std::size_t i = 0; i < s.stages.size(); ++i) {
            total.stages[i].name = s.stages[i].name;
            total.stages[i].index = static_cast<std::uint32_t>(i + 1);
        }
        std::vector<bool> stage_started(s.stages.size(), false);
        bool have_metadata = false;
        std::uint32_t peak_connections = 0;
        double peak_rate = 0;
        double elapsed_before = 0;
        std::uint64_t transactions_before = 0;
        std::uint64_t engine_runs = 0;
        out.ok = true;
        for (std::size_t k = 0; k < steps.size(); ++k) {
            const StageStep& step = steps[k];
            if (hooks.stop != nullptr && hooks.stop->load()) break;
            stats::StageResult& stage = total.stages[step.stage];
            if (!stage_started[step.stage]) {
                stage_started[step.stage] = true;
                stage.start_offset_ns = total.metadata.measured_duration_ns;
            }
            if (is_idle(plan, step)) {
                idle_for(step.duration, hooks.stop);
                total.metadata.measured_duration_ns +=
                    static_cast<std::uint64_t>(step.duration.count());
                elapsed_before += std::chrono::duration<double>(step.duration).count();
                stage.end_offset_ns = total.metadata.measured_duration_ns;
                continue;
            }
            load::Plan step_plan = plan;
            const bool first_run = engine_runs == 0;
            step_plan.warmup = first_run ? plan.warmup : load::Duration::zero();
            step_plan.duration = step.duration + step_plan.warmup;
            step_plan.transactions = 0;
            step_plan.rate = plan.model == load::LoadModel::OpenLoop ? step.rate : 0;
            step_plan.connections = step.connections;
            step_plan.seed = plan.seed + k;
            const std::uint64_t intervals_before = total.timeline.size();
            if (hooks.on_progress) {
                eo.on_progress = [&, intervals_before](const load::ProgressSnapshot& snap) {
                    load::ProgressSnapshot shifted = snap;
                    shifted.interval_index += intervals_before;
                    shifted.elapsed_seconds += elapsed_before;
                    shifted.total_transactions += transactions_before;
                    hooks.on_progress(shifted);
                };
            }
            load::LoadResult r = load::run_load(step_plan, eo);
            ++engine_runs;
            for (auto& w : r.warnings) {
                if (std::find(out.warnings.begin(), out.warnings.end(), w) == out.warnings.end()) {
                    out.warnings.push_back(std::move(w));
                }
            }
            if (!have_metadata && r.run.counters.transactions_sent > 0) {
                const std::uint64_t measured = total.metadata.measured_duration_ns;
                total.metadata = r.run.metadata;
                total.metadata.measured_duration_ns = measured;
                have_metadata = true;
            }
            peak_connections = std::max(peak_connections, step.connections);
            peak_rate = std::max(peak_rate, step_plan.rate);
            merge_step(total, r.run, &stage);
            stage.end_offset_ns = total.metadata.measured_duration_ns;
            elapsed_before += std::chrono::duration<double>(step_plan.duration).count();
            transactions_before = total.counters.completed();
            out.pending_at_end += r.pending_at_end;
            out.late_responses += r.late_responses;
            out.framing_errors += r.framing_errors;
            out.bad_protocol_frames += r.bad_protocol_frames;
            if (!r.ok) {
                out.ok = false;
                out.error = r.error;
                if (!have_metadata) total.metadata = r.run.metadata;
                break;
            }
        }
        total.metadata.connections = peak_connections;
        total.metadata.rate_per_second = peak_rate;
        total.metadata.requested_duration_ns =
            static_cast<std::uint64_t>(s.total_duration().count());
        total.metadata.warmup_ns = static_cast<std::uint64_t>(plan.warmup.count());
        total.metadata.notes.push_back(fmt::format(
            "stages: {} stage{} run as {} engine run{} (ramps in steps of at most {}s; "
            "connections re-open at each step)",
            s.stages.size(), s.stages.size() == 1 ? "" : "s", engine_runs,
            engine_runs == 1 ? "" : "s", std::chrono::duration<double>(s.stage_step).count()));
        out.run = std::move(total);
    }

    if (embedded) {
        out.run.metadata.notes.push_back(
            fmt::format("target: embedded reference slave on {}", embedded->endpoint()));
        embedded->stop();
    } else if (!s.slave_yaml.empty()) {
        out.run.metadata.notes.push_back("slave: settings not used (a target was given)");
    }
    if (!s.name.empty()) out.run.metadata.notes.push_back("scenario: " + s.name);
    evaluate_thresholds(s, out.run);
    return out;
}

}  // namespace mbstorm::scenario
