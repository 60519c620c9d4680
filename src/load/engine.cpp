#include "load/engine.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <thread>

#include "load/preflight.hpp"
#include "load/worker.hpp"
#include "load/write_safety.hpp"
#include "net/clock.hpp"

namespace mbstorm::load {
namespace {

// Splits `total` over `parts` as evenly as possible; part i gets the i-th share.
std::uint64_t share(std::uint64_t total, std::uint32_t parts, std::uint32_t i) {
    return total / parts + (i < total % parts ? 1 : 0);
}

void merge_results(const Plan& plan, std::vector<std::unique_ptr<Worker>>& workers,
                   LoadResult& result) {
    stats::RunResult& run = result.run;
    run.operations.clear();
    for (std::size_t op = 0; op < plan.operations.size(); ++op) {
        stats::OperationResult merged;
        merged.name = workers.front()->operations[op].name;
        merged.function_code = workers.front()->operations[op].function_code;
        for (auto& w : workers) {
            merged.latency.add(w->operations[op].latency);
            merged.counters.add(w->operations[op].counters);
        }
        run.latency.add(merged.latency);
        run.counters.add(merged.counters);
        run.operations.push_back(std::move(merged));
    }
    for (auto& w : workers) {
        run.counters.add(w->stray);
        run.schedule_lag.late_sends += w->schedule_lag.late_sends;
        run.schedule_lag.total_lag_ns += w->schedule_lag.total_lag_ns;
        run.schedule_lag.max_lag_ns =
            std::max(run.schedule_lag.max_lag_ns, w->schedule_lag.max_lag_ns);
        run.connections.opened += w->connection_stats.opened;
        run.connections.failed += w->connection_stats.failed;
        run.connections.reconnects += w->connection_stats.reconnects;
        run.connections.closed_by_peer += w->connection_stats.closed_by_peer;
        result.pending_at_end += w->pending_at_end;
        result.late_responses += w->late_responses;
        result.framing_errors += w->framing_errors;
        result.bad_protocol_frames += w->bad_protocol_frames;
    }
}

}  // namespace

std::uint64_t transactions_accounted(const stats::OutcomeCounters& counters) noexcept {
    return counters.completed() - counters.count(stats::Outcome::UnknownId) -
           counters.count(stats::Outcome::DuplicateId);
}

LoadResult run_load(const Plan& plan, const EngineOptions& options) {
    LoadResult result;
    if (const auto errors = validate_plan(plan); !errors.empty()) {
        result.error = fmt::format("invalid plan: {}", fmt::join(errors, "; "));
        return result;
    }
    const std::string target = endpoint_text(plan.host, plan.port);
    net::Endpoint endpoint;
    std::string resolve_error;
    if (!net::parse_endpoint(target, endpoint, &resolve_error, plan.port)) {
        result.error = fmt::format("cannot resolve {}: {}", target, resolve_error);
        return result;
    }
    const WriteSafetyVerdict verdict = check_write_safety(plan, numeric_address(endpoint));
    if (!verdict.allowed) {
        result.error = verdict.message;
        return result;
    }
    const std::uint32_t threads = effective_threads(plan);
    if (std::string why = check_connection_capacity(plan.connections, threads); !why.empty()) {
        result.error = std::move(why);
        return result;
    }

    const std::int64_t interval_ns = std::max<std::int64_t>(options.progress_interval_ns, 1000);
    const std::size_t max_intervals =
        plan.duration.count() > 0
            ? static_cast<std::size_t>(plan.duration.count() / interval_ns) + 16
            : 86400;
    stats::IntervalTimeline timeline(static_cast<std::uint64_t>(interval_ns), threads,
                                     max_intervals);

    std::atomic<bool> abort{false};
    std::atomic<bool> any_connected{false};
    const auto wall_start = std::chrono::system_clock::now();
    const std::int64_t start_ns = net::now_ns();
    const std::int64_t measure_start_ns = start_ns + plan.warmup.count();
    const std::int64_t end_ns =
        plan.duration.count() > 0 ? start_ns + plan.duration.count() : INT64_MAX;

    std::vector<std::unique_ptr<Worker>> workers;
    workers.reserve(threads);
    for (std::uint32_t i = 0; i < threads; ++i) {
        WorkerSetup setup;
        setup.plan = &plan;
        setup.endpoint = endpoint;
        setup.target = endpoint.to_string();
        setup.index = i;
        setup.connections = static_cast<std::uint32_t>(share(plan.connections, threads, i));
        const double fraction = static_cast<double>(setup.connections) / plan.connections;
        setup.quota = plan.transactions == 0
                          ? 0
                          : std::max<std::uint64_t>(share(plan.transactions, threads, i), 1);
        setup.rate = plan.rate * fraction;
        setup.connect_rate = plan.connect_rate / threads;
        setup.start_ns = start_ns;
        setup.measure_start_ns = measure_start_ns;
        setup.end_ns = end_ns;
        setup.stop = options.stop;
        setup.abort = &abort;
        setup.any_connected = &any_connected;
        setup.verifier = options.verifier;
        setup.timeline = &timeline;
        workers.push_back(std::make_unique<Worker>(std::move(setup)));
    }

    std::atomic<std::uint32_t> finished{0};
    std::vector<std::thread> pool;
    pool.reserve(threads);
    for (auto& w : workers) {
        pool.emplace_back([&finished, worker = w.get()] {
            worker->run();
            finished.fetch_add(1);
        });
    }

    // Progress: report each interval once every worker has moved past it.
    std::uint64_t reported = UINT64_MAX;
    std::uint64_t total_transactions = 0;
    while (finished.load() < threads) {
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
        if (!options.on_progress) continue;
        const auto latest = timeline.latest();
        if (!latest || latest->index == reported) continue;
        // Only whole intervals: the last, partial one of a run would show a false rate.
        const auto interval_end =
            static_cast<std::int64_t>((latest->index + 1) * latest->duration_ns);
        if (measure_start_ns + interval_end > std::min(net::now_ns(), end_ns)) continue;
        reported = latest->index;
        total_transactions += latest->transactions;
        ProgressSnapshot snap;
        snap.interval_index = latest->index;
        snap.elapsed_seconds = static_cast<double>(net::now_ns() - start_ns) / 1e9;
        snap.transactions_per_second = latest->transactions_per_second();
        snap.p50_ns = latest->p50_ns;
        snap.p99_ns = latest->p99_ns;
        snap.max_ns = latest->max_ns;
        snap.errors = latest->errors;
        snap.total_transactions = total_transactions;
        for (auto& w : workers) snap.open_connections += w->open_connections.load();
        options.on_progress(snap);
    }
    for (auto& t : pool) t.join();
    timeline.finish();

    merge_results(plan, workers, result);
    std::int64_t finished_ns = measure_start_ns;
    for (auto& w : workers) {
        finished_ns = std::max(finished_ns, w->finished_ns);
        if (result.error.empty() && !w->fatal_error.empty()) result.error = w->fatal_error;
    }
    result.ok = result.error.empty();

    stats::RunMetadata& meta = result.run.metadata;
    meta.tool_version = options.tool_version;
    meta.target = endpoint.to_string();
    meta.threads = threads;
    meta.connections = plan.connections;
    meta.depth = plan.depth;
    meta.model =
        plan.model == LoadModel::OpenLoop ? stats::LoadModel::Open : stats::LoadModel::Closed;
    meta.rate_per_second = plan.model == LoadModel::OpenLoop ? plan.rate : 0.0;
    meta.requested_duration_ns = static_cast<std::uint64_t>(plan.duration.count());
    meta.measured_duration_ns = static_cast<std::uint64_t>(finished_ns - measure_start_ns);
    meta.warmup_ns = static_cast<std::uint64_t>(plan.warmup.count());
    meta.start_time = wall_start;
    if (plan.model == LoadModel::OpenLoop) {
        meta.notes.push_back(
            "open loop: latency measured from each request's intended send time (coordinated "
            "omission corrected)");
    }
    result.run.timeline = timeline.summaries();
    result.run.timeline_interval_ns = static_cast<std::uint64_t>(interval_ns);
    // The run rarely ends on an interval boundary: drop empty intervals past the end and give
    // the last one its real length, so its throughput is not understated.
    auto& series = result.run.timeline;
    while (!series.empty() && series.back().transactions == 0 &&
           series.back().start_offset_ns >= meta.measured_duration_ns)
        series.pop_back();
    if (!series.empty() && series.back().start_offset_ns < meta.measured_duration_ns &&
        series.back().start_offset_ns + series.back().duration_ns > meta.measured_duration_ns)
        series.back().duration_ns = meta.measured_duration_ns - series.back().start_offset_ns;
    if (!verdict.write_operations.empty()) {
        result.warnings.push_back(fmt::format("write operations sent to {}: {}", meta.target,
                                              fmt::join(verdict.write_operations, ", ")));
    }
    return result;
}

}  // namespace mbstorm::load
