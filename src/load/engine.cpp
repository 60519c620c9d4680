#include "load/engine.hpp"
#include "load/foreign_protocol.hpp"
#include "load/serial_load.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <functional>
#include <memory>
#include <optional>
#include <thread>

#include "load/preflight.hpp"
#include "load/stage_schedule.hpp"
#include "load/thread_share.hpp"
#include "load/worker.hpp"
#include "load/write_safety.hpp"
#include "net/clock.hpp"
#include "net/features.hpp"
#include "net/kernel_tls.hpp"
#include "net/serial_port.hpp"
#include "net/source_addresses.hpp"

namespace mbstorm::load {
namespace {

// No connection open for this long after one was: the target is lost (a reconnect after a
// dropped connection takes far less).
constexpr std::int64_t kTargetLostAfterNs = 500 * net::kNsPerMs;

// When the target went away and came back (back_ns < 0: not back by the end).
struct Outage {
    std::int64_t lost_ns = 0;
    std::int64_t back_ns = -1;
};

// Watches the open-connection count during the run for outages of the target.
class OutageWatch {
  public:
    void sample(std::uint32_t open, std::int64_t now) {
        if (open > 0) {
            if (!outages_.empty() && outages_.back().back_ns < 0) outages_.back().back_ns = now;
            seen_open_ = true;
            zero_since_ = -1;
            return;
        }
        if (!seen_open_) return;
        if (zero_since_ < 0) zero_since_ = now;
        const bool recorded = !outages_.empty() && outages_.back().back_ns < 0;
        if (!recorded && now - zero_since_ >= kTargetLostAfterNs)
            outages_.push_back({zero_since_, -1});
    }
    // A stage that wants no connection: none open is no outage.
    void none_wanted() { zero_since_ = -1; }
    const std::vector<Outage>& outages() const { return outages_; }

  private:
    bool seen_open_ = false;
    std::int64_t zero_since_ = -1;
    std::vector<Outage> outages_;
};

std::string offset_text(std::int64_t t, std::int64_t measure_start_ns) {
    if (t < measure_start_ns) return "during warm-up";
    return fmt::format("at {:.2f}s", static_cast<double>(t - measure_start_ns) / 1e9);
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
        run.service_time.add(w->service_time);
        run.counters.add(w->stray);
        run.schedule_lag.engine.add(w->schedule_lag.engine);
        run.schedule_lag.target.add(w->schedule_lag.target);
        run.connections.opened += w->connection_stats.opened;
        run.connections.failed += w->connection_stats.failed;
        run.connections.reconnects += w->connection_stats.reconnects;
        run.connections.closed_by_peer += w->connection_stats.closed_by_peer;
        run.connections.tls_handshakes += w->connection_stats.tls_handshakes;
        run.connections.tls_resumed += w->connection_stats.tls_resumed;
        run.connections.tls_handshake_failures += w->connection_stats.tls_handshake_failures;
        run.connections.tls_offloaded += w->connection_stats.tls_offloaded;
        run.connections.tls_offload_errors += w->connection_stats.tls_offload_errors;
        run.connections.tls_handshake_ns_total += w->connection_stats.tls_handshake_ns_total;
        run.connections.tls_handshake_ns_max = std::max(run.connections.tls_handshake_ns_max,
                                                        w->connection_stats.tls_handshake_ns_max);
        run.connections.peak_open += w->connection_stats.peak_open;
        for (std::size_t e = 0; e < w->connect_failures_by_errno.size(); ++e) {
            if (w->connect_failures_by_errno[e] == 0) continue;
            const char* name = e == 0 ? nullptr : strerrorname_np(static_cast<int>(e));
            run.connections.failed_by_cause[name != nullptr ? name : fmt::format("errno {}", e)] +=
                w->connect_failures_by_errno[e];
        }
        run.pipelining.skipped_requests += w->skipped_requests;
        for (std::size_t i = 0; i < w->stages.size(); ++i) {
            stats::StageResult& into = run.stages[i];
            const stats::StageResult& from = w->stages[i];
            into.latency.add(from.latency);
            into.counters.add(from.counters);
            if (into.operations.empty() && !from.operations.empty()) {
                for (const auto& op : from.operations) {
                    stats::OperationResult empty;
                    empty.name = op.name;
                    empty.function_code = op.function_code;
                    into.operations.push_back(std::move(empty));
                }
            }
            for (std::size_t op = 0; op < from.operations.size(); ++op) {
                into.operations[op].latency.add(from.operations[op].latency);
                into.operations[op].counters.add(from.operations[op].counters);
            }
        }
        result.pending_at_end += w->pending_at_end;
        result.late_responses += w->late_responses;
        result.framing_errors += w->framing_errors;
        result.unframed_bytes += w->unframed_bytes;
        if (result.unframed_sample.empty())
            result.unframed_sample.assign(w->unframed_sample.begin(),
                                          w->unframed_sample.begin() + w->unframed_sample_size);
        result.crc_errors += w->crc_errors;
        result.bad_protocol_frames += w->bad_protocol_frames;
    }
}

// "9,326": counts in shortfall texts read like the rest of the report.
std::string grouped(double value) {
    const std::string digits = fmt::format("{:.0f}", value);
    std::string out;
    out.reserve(digits.size() + digits.size() / 3);
    for (std::size_t i = 0; i < digits.size(); ++i) {
        if (i != 0 && (digits.size() - i) % 3 == 0) out.push_back(',');
        out.push_back(digits[i]);
    }
    return out;
}

// What the plan asked for and the run did not do, each said plainly (see PlanShortfall).
void note_shortfalls(const Plan& plan, const StageSchedule& schedule, bool stopped,
                     stats::RunResult& run) {
    const stats::RunMetadata& m = run.metadata;
    // A transaction count that was reached ends the run as planned: nothing was cut short.
    const bool count_reached =
        plan.transactions != 0 && run.counters.transactions_sent >= plan.transactions;
    if (count_reached) return;
    auto add = [&run](std::string what, double planned, double achieved, std::string text) {
        run.shortfalls.push_back({std::move(what), planned, achieved, std::move(text)});
    };
    const auto seconds = [](std::uint64_t ns) { return static_cast<double>(ns) / 1e9; };
    // The loop ends at or after the planned end; 1 ms of slack for clock granularity.
    if (m.requested_duration_ns != 0 &&
        m.measured_duration_ns + 1'000'000 < m.requested_duration_ns) {
        add("duration", seconds(m.requested_duration_ns), seconds(m.measured_duration_ns),
            fmt::format("duration: {:.3g}s measured of {:.3g}s planned ({})",
                        seconds(m.measured_duration_ns), seconds(m.requested_duration_ns),
                        stopped ? "stopped early" : "the run ended early"));
    }
    if (run.connections.peak_open < m.connections) {
        add("connections", m.connections, static_cast<double>(run.connections.peak_open),
            fmt::format("connections: {} of {} opened ({} connect attempts failed)",
                        grouped(static_cast<double>(run.connections.peak_open)),
                        grouped(m.connections),
                        grouped(static_cast<double>(run.connections.failed))));
    }
    if (plan.model == LoadModel::OpenLoop) {
        const auto window = static_cast<std::int64_t>(std::min(
            m.measured_duration_ns,
            m.requested_duration_ns == 0 ? m.measured_duration_ns : m.requested_duration_ns));
        const double scheduled = schedule.scheduled_transactions(window);
        const auto sent = static_cast<double>(run.counters.transactions_sent);
        // 5% of slack: the schedule starts with the first connection, a hair after the run.
        if (scheduled >= 20.0 && sent < 0.95 * scheduled) {
            const double span = seconds(static_cast<std::uint64_t>(window));
            add("rate", scheduled / span, sent / span,
                fmt::format("rate: {} of the {} transactions the schedule asked for were sent "
                            "({} of {} req/s)",
                            grouped(sent), grouped(scheduled), grouped(sent / span),
                            grouped(scheduled / span)));
        }
    }
}

// Each stage's name and the targets it moves between; offsets come after the run.
// The run ended before any connection was set up, and none failed: a silent target, or a run
// shorter than setting its connections up. One connect now tells which (a target that is up
// answers it at once), so that the second is not reported as an unreachable target.
Error no_connection_error(const Plan& plan, const net::Endpoint& target, double ran_s) {
    using namespace std::chrono;
    const double timeout_s = duration<double>(plan.connect_timeout).count();
    const auto probe_ms =
        duration_cast<milliseconds>(std::min<nanoseconds>(plan.connect_timeout, 1s));
    if (net::connect_within(target, static_cast<int>(probe_ms.count())) == 0) {
        return Error(ErrorCode::Interrupted,
                     fmt::format("the run ended after {:.3g}s, before any of its {} connection(s) "
                                 "to {} was set up (the target accepts connections): nothing was "
                                 "measured; run for longer (-d)",
                                 ran_s, plan.connections, target.to_string()));
    }
    return Error(ErrorCode::Network,
                 fmt::format("cannot connect to {}: no connection was established during the "
                             "run ({:.3g}s; connect timeout {:.3g}s)",
                             target.to_string(), ran_s, timeout_s));
}

void describe_stages(const Plan& plan, const StageSchedule& schedule,
                     std::vector<stats::StageResult>& stages) {
    if (!schedule.empty()) {
        stages.resize(schedule.stages());
        for (std::size_t i = 0; i < schedule.stages(); ++i) {
            stats::StageResult& stage = stages[i];
            stage.index = static_cast<std::uint32_t>(i + 1);
            stage.name =
                plan.stages[i].name.empty() ? fmt::format("stage {}", i + 1) : plan.stages[i].name;
            const StageTargets from = schedule.stage_from(i);
            const StageTargets to = schedule.stage_to(i);
            stage.rate_from = from.rate;
            stage.rate_to = to.rate;
            stage.connections_from = from.connections;
            stage.connections_to = to.connections;
        }
    }
}

// The run rarely ends on an interval boundary: drop empty intervals past the end and give
// the last one its real length, so its throughput is not understated.
void fit_timeline_to_run(std::vector<stats::IntervalSummary>& series, std::uint64_t measured_ns,
                         std::int64_t interval_ns) {
    while (!series.empty() && series.back().transactions == 0 &&
           series.back().start_offset_ns >= measured_ns)
        series.pop_back();
    if (!series.empty() && series.back().start_offset_ns < measured_ns &&
        series.back().start_offset_ns + series.back().duration_ns > measured_ns)
        series.back().duration_ns = measured_ns - series.back().start_offset_ns;
    // A sliver of an interval at the very end would plot as a false spike or dip: fold it into
    // the interval before (counts add; the percentiles stay those of the full interval).
    if (series.size() >= 2 &&
        series.back().duration_ns * 2 < static_cast<std::uint64_t>(interval_ns)) {
        const stats::IntervalSummary sliver = series.back();
        series.pop_back();
        stats::IntervalSummary& last = series.back();
        last.transactions += sliver.transactions;
        last.errors += sliver.errors;
        last.latency_count += sliver.latency_count;
        last.max_ns = std::max(last.max_ns, sliver.max_ns);
        last.duration_ns += sliver.duration_ns;
    }
}

// Where each stage started and ended within the measured time.
void place_stages(const StageSchedule& schedule, std::uint64_t measured_ns,
                  std::vector<stats::StageResult>& stages) {
    for (std::size_t i = 0; i < stages.size(); ++i) {
        // A run stopped early ends its stages where measuring ended.
        auto clip = [&](std::int64_t t) {
            return std::min(static_cast<std::uint64_t>(t), measured_ns);
        };
        stages[i].start_offset_ns = clip(schedule.stage_start_ns(i));
        stages[i].end_offset_ns = clip(schedule.stage_end_ns(i));
    }
    // The last stage ends where measuring ended (a run stops a hair after its schedule).
    if (!stages.empty()) stages.back().end_offset_ns = measured_ns;
}

// One note per outage: when the target was lost and when (if) it came back.
void note_outages(const OutageWatch& outages, std::int64_t measure_start_ns, LoadResult& result) {
    for (const Outage& o : outages.outages()) {
        if (o.back_ns >= 0) {
            result.run.metadata.notes.push_back(fmt::format(
                "target lost {} (no connection open), back {} ({:.2f}s without a connection)",
                offset_text(o.lost_ns, measure_start_ns), offset_text(o.back_ns, measure_start_ns),
                static_cast<double>(o.back_ns - o.lost_ns) / 1e9));
        } else {
            result.target_lost_at_end = true;
            result.run.metadata.notes.push_back(fmt::format(
                "target lost {} (no connection open) and not back by the end of the run",
                offset_text(o.lost_ns, measure_start_ns)));
        }
    }
}

// The plan's source addresses, each checked to be of the target's family and local.
Error resolve_sources(const Plan& plan, const net::Endpoint& target,
                      std::vector<net::Endpoint>& sources) {
    Result<std::vector<net::Endpoint>> parsed = net::parse_source_addresses(plan.source_addresses);
    if (!parsed.ok()) return Error(parsed.error().code(), "source_addr: " + parsed.error().text());
    sources = std::move(parsed).value();
    for (const net::Endpoint& source : sources) {
        if (source.family() != target.family()) {
            return Error(
                ErrorCode::InvalidInput,
                fmt::format("source_addr: {} is {} but the target {} is {}",
                            numeric_address(source), source.family() == AF_INET ? "IPv4" : "IPv6",
                            target.to_string(), target.family() == AF_INET ? "IPv4" : "IPv6"));
        }
        if (Error why = net::check_source_is_local(source); !why.ok())
            return Error(why.code(), "source_addr: " + why.text());
    }
    return {};
}

// When the run starts, starts measuring and ends (INT64_MAX: when its transactions are done).
struct RunWindow {
    std::int64_t connect_start_ns = 0;
    std::int64_t start_ns = 0;
    std::int64_t measure_start_ns = 0;
    std::int64_t end_ns = 0;
};

// What the workers share with the engine's thread while they run.
struct WorkerLinks {
    const EngineOptions& options;
    std::atomic<bool>& abort;
    std::atomic<bool>& any_connected;
    stats::IntervalTimeline& timeline;
    bool direct_descriptors = false;
    net::Backend backend = net::Backend::IoUring;
};

// One worker per thread, each with its share of the connections, the quota and the rate.
std::vector<std::unique_ptr<Worker>> make_workers(const Plan& plan, const net::Endpoint& endpoint,
                                                  const std::vector<net::Endpoint>& sources,
                                                  std::uint32_t threads, std::uint32_t capacity,
                                                  const RunWindow& window,
                                                  const StageSchedule& schedule,
                                                  const WorkerLinks& links) {
    std::vector<std::unique_ptr<Worker>> workers;
    workers.reserve(threads);
    std::uint32_t first_connection = 0;
    for (std::uint32_t i = 0; i < threads; ++i) {
        WorkerSetup setup;
        setup.plan = &plan;
        setup.endpoint = endpoint;
        setup.sources = &sources;
        if (!sources.empty() && !read_port_range(setup.ports)) setup.ports = PortRange{1, 0};
        if (!sources.empty())
            setup.ports_in_use =
                static_cast<std::uint32_t>((capacity + sources.size() - 1) / sources.size());
        setup.first_connection = first_connection;
        setup.target = endpoint.to_string();
        setup.index = i;
        setup.threads = threads;
        setup.connections = static_cast<std::uint32_t>(thread_share(capacity, threads, i));
        first_connection += setup.connections;
        const double fraction = static_cast<double>(setup.connections) / capacity;
        setup.quota = plan.transactions == 0
                          ? 0
                          : std::max<std::uint64_t>(thread_share(plan.transactions, threads, i), 1);
        setup.rate = plan.rate * fraction;
        setup.connect_rate = plan.connect_rate / threads;
        setup.connect_start_ns = window.connect_start_ns;
        setup.start_ns = window.start_ns;
        setup.measure_start_ns = window.measure_start_ns;
        setup.end_ns = window.end_ns;
        setup.stop = links.options.stop;
        setup.abort = &links.abort;
        setup.any_connected = &links.any_connected;
        setup.verifier = links.options.verifier;
        setup.timeline = &links.timeline;
        setup.schedule = schedule.empty() ? nullptr : &schedule;
        setup.direct_descriptors = links.direct_descriptors;
        setup.backend = links.backend;
        setup.live = links.options.live != nullptr ? links.options.live->worker(i) : nullptr;
        workers.push_back(std::make_unique<Worker>(std::move(setup)));
    }

    return workers;
}

// --metrics-listen's rate gauges: what the plan asks for now (open loop) and what the last full
// interval achieved.
void publish_rates(const Plan& plan, const StageSchedule& schedule, std::int64_t measure_start_ns,
                   const stats::IntervalTimeline& timeline, LiveMetrics& live) {
    double target = 0;
    if (plan.model == LoadModel::OpenLoop) {
        const std::int64_t offset = std::max<std::int64_t>(net::now_ns() - measure_start_ns, 0);
        target = schedule.empty() ? plan.rate : schedule.at(offset).rate;
    }
    const auto latest = timeline.latest();
    live.set_rates(target, latest ? latest->transactions_per_second() : 0.0);
}

// What run_load settles before a socket opens: where to, from where, how many rings.
struct RunSetup {
    net::Endpoint endpoint;
    std::vector<net::Endpoint> sources;
    WriteSafetyVerdict verdict;
    std::uint32_t capacity = 0;  // the most connections open at once (the peak stage's)
    std::uint32_t threads = 0;
    bool direct = false;  // sockets as io_uring direct descriptors
    net::BackendDecision backend;
};

// Where the (valid) plan's connections go and from where, and whether the machine can hold
// them; an error when it cannot run against its target.
Error prepare_run(const Plan& plan, const EngineOptions& options, const StageSchedule& schedule,
                  RunSetup& setup) {
    const std::string target = endpoint_text(plan.host, plan.port);
    Result<net::Endpoint> endpoint = net::parse_endpoint(target, plan.port);
    if (!endpoint.ok())
        return Error(endpoint.error().code(),
                     fmt::format("cannot resolve {}: {}", target, endpoint.error().text()));
    setup.endpoint = *endpoint;
    setup.verdict = check_write_safety(plan, numeric_address(setup.endpoint));
    if (!setup.verdict.allowed()) return setup.verdict.refusal;
    if (Error why = resolve_sources(plan, setup.endpoint, setup.sources); !why.ok()) return why;
    setup.capacity = schedule.peak_connections();
    Result<net::BackendDecision> backend = net::choose_backend(options.backend, true);
    if (!backend.ok()) return backend.error();
    setup.backend = *backend;
    // The kernel's TLS (where there is one) needs descriptors setsockopt can reach.
    setup.direct = setup.backend.backend == net::Backend::IoUring &&
                   options.use_direct_descriptors && net::features().direct_descriptors &&
                   !(plan.tls && net::kernel_tls().available);
    setup.threads = effective_threads(plan);
    // Threads left to the engine: as many rings as the connections' socket tables need.
    if (setup.direct && plan.threads == 0)
        setup.threads = threads_for_socket_tables(setup.capacity, setup.threads);
    Error why = check_connection_capacity(setup.capacity, setup.threads, setup.sources.size(),
                                          setup.direct);
    // Only io_uring's direct descriptors escape the open-files limit.
    if (!why.ok() && setup.backend.backend == net::Backend::Epoll)
        return Error(why.code(),
                     why.message() + " (the epoll backend holds each connection as a descriptor)");
    return why;
}

// run --serial: one master on the line, one request at a time; writes need leave unless the
// line is a pseudo-terminal (a test).
Error prepare_serial_run(const Plan& plan, RunSetup& setup) {
    const bool test_line = net::is_pseudo_terminal(plan.serial.device);
    setup.verdict = check_write_safety(
        plan.operations, test_line ? "127.0.0.1" : plan.serial.device, plan.allow_writes);
    if (!setup.verdict.allowed()) return setup.verdict.refusal;
    setup.capacity = 1;
    setup.threads = 1;
    return {};
}

// What the serial line measured, as merge_results gathers the workers'.
void take_serial_results(SerialRunner& line, LoadResult& result) {
    stats::RunResult& run = result.run;
    run.operations = std::move(line.operations);
    for (const auto& op : run.operations) run.latency.add(op.latency);
    run.service_time.add(line.service_time);
    run.counters = line.counters;
    run.schedule_lag.target = line.target_lag;
    run.connections.opened = 1;
    run.connections.peak_open = 1;
    for (std::size_t i = 0; i < line.stages.size() && i < run.stages.size(); ++i) {
        run.stages[i].latency.add(line.stages[i].latency);
        run.stages[i].counters.add(line.stages[i].counters);
        run.stages[i].operations = std::move(line.stages[i].operations);
    }
    result.crc_errors = line.bad_checks;
    result.error = line.fatal_error;
}

// The run's clock: connections open at once; requests (warm-up first) wait for --start-at, if
// any; a start-at already past starts at once and is remembered as lateness.
struct RunClock {
    RunWindow window;
    std::chrono::system_clock::time_point wall_start;  // when requests begin, wall-clock
    std::uint64_t late_by_ns = 0;
};

RunClock start_clock(const Plan& plan, const EngineOptions& options, std::int64_t run_ns) {
    RunClock clock;
    clock.wall_start = std::chrono::system_clock::now();
    clock.window.connect_start_ns = net::now_ns();
    std::int64_t start_ns = clock.window.connect_start_ns;
    if (options.start_at) {
        const std::int64_t ahead = std::chrono::duration_cast<std::chrono::nanoseconds>(
                                       *options.start_at - clock.wall_start)
                                       .count();
        if (ahead > 0) {
            start_ns += ahead;
            clock.wall_start = *options.start_at;
        } else {
            clock.late_by_ns = static_cast<std::uint64_t>(-ahead);
        }
    }
    clock.window.start_ns = start_ns;
    clock.window.measure_start_ns = start_ns + plan.warmup.count();
    clock.window.end_ns = run_ns > 0 ? start_ns + run_ns : INT64_MAX;
    return clock;
}

// What the engine's thread does while the workers run, one look every 10 ms: outages of the
// target, the most connections open in each interval, whole intervals handed to --timeline and
// the progress line, histograms to --hlog, and the live rate gauges.
class RunWatch {
  public:
    RunWatch(const Plan& plan, const EngineOptions& options, const StageSchedule& schedule,
             const RunClock& clock, stats::IntervalTimeline& timeline,
             std::function<std::uint32_t()> open_now, std::size_t max_intervals)
        : plan_(plan),
          options_(options),
          schedule_(schedule),
          window_(clock.window),
          measure_start_wall_(
              clock.wall_start +
              std::chrono::duration_cast<std::chrono::system_clock::duration>(plan.warmup)),
          timeline_(timeline),
          open_now_(std::move(open_now)),
          max_intervals_(max_intervals) {
        open_by_interval_.reserve(max_intervals);
        fresh_.reserve(64);
        // Built once: a std::function made per drain could allocate in the steady state.
        hand_over_ = [this](const stats::IntervalHistograms& interval) {
            options_.on_interval_histograms(interval, measure_start_wall_);
        };
    }

    void look(bool stopping) {
        drain_histograms();
        // Only while the run is meant to go on: at its end the connections close anyway.
        if (const std::int64_t now = net::now_ns(); now < window_.end_ns && !stopping)
            watch_outages(now);
        note_open_connections();
        stream_whole_intervals();
        if (options_.live != nullptr)
            publish_rates(plan_, schedule_, window_.measure_start_ns, timeline_, *options_.live);
        report_progress();
    }

    void drain_histograms() {
        if (options_.on_interval_histograms) timeline_.drain_histograms(hand_over_);
    }

    // What the engine adds to an interval's summary: the most connections seen open in it
    // and, in open loop, the rate scheduled at its midpoint.
    void complete_interval(stats::IntervalSummary& iv) const {
        if (iv.index < open_by_interval_.size()) iv.open_connections = open_by_interval_[iv.index];
        if (plan_.model != LoadModel::OpenLoop) return;
        const auto mid = static_cast<std::int64_t>(iv.start_offset_ns + iv.duration_ns / 2);
        iv.target_rate = schedule_.at(mid).rate;  // the plan's rate when there are no stages
    }

    // After the run: every interval --timeline has not had yet.
    void stream_the_rest(std::vector<stats::IntervalSummary>& series) const {
        if (!options_.on_interval) return;
        for (const auto& iv : series)
            if (iv.index >= streamed_) options_.on_interval(iv, measure_start_wall_);
    }

    const OutageWatch& outages() const { return outages_; }

  private:
    std::uint32_t open_now() const { return open_now_(); }

    void watch_outages(std::int64_t now) {
        const bool wanted =
            schedule_.empty() ||
            schedule_.at(std::max<std::int64_t>(now - window_.measure_start_ns, 0)).connections > 0;
        if (wanted)
            outages_.sample(open_now(), now);
        else
            outages_.none_wanted();
    }

    void note_open_connections() {
        const std::int64_t now = net::now_ns();
        if (now < window_.measure_start_ns) return;
        const auto index =
            static_cast<std::size_t>((now - window_.measure_start_ns) / timeline_interval_ns());
        if (index >= max_intervals_) return;
        if (open_by_interval_.size() <= index) open_by_interval_.resize(index + 1, 0);
        open_by_interval_[index] = std::max(open_by_interval_[index], open_now());
    }

    std::int64_t timeline_interval_ns() const {
        return static_cast<std::int64_t>(timeline_.interval_ns());
    }

    void stream_whole_intervals() {
        if (!options_.on_interval) return;
        const std::int64_t whole_before = std::min(net::now_ns(), window_.end_ns);
        timeline_.copy_summaries(streamed_, fresh_);
        for (stats::IntervalSummary& iv : fresh_) {
            const auto iv_end = static_cast<std::int64_t>(iv.start_offset_ns + iv.duration_ns);
            if (window_.measure_start_ns + iv_end > whole_before) break;
            // The run's last interval may still take in the sliver after the end
            // (fit_timeline_to_run): it goes out after the run, with it.
            if (window_.measure_start_ns + iv_end >= window_.end_ns) break;
            complete_interval(iv);
            options_.on_interval(iv, measure_start_wall_);
            ++streamed_;
        }
    }

    // Each interval once every worker has moved past it; only whole intervals: the last,
    // partial one of a run would show a false rate.
    void report_progress() {
        if (!options_.on_progress) return;
        const auto latest = timeline_.latest();
        if (!latest || latest->index == reported_) return;
        const auto interval_end =
            static_cast<std::int64_t>((latest->index + 1) * latest->duration_ns);
        if (window_.measure_start_ns + interval_end > std::min(net::now_ns(), window_.end_ns))
            return;
        reported_ = latest->index;
        total_transactions_ += latest->transactions;
        ProgressSnapshot snap;
        snap.interval_index = latest->index;
        snap.elapsed_seconds = static_cast<double>(net::now_ns() - window_.start_ns) / 1e9;
        snap.transactions_per_second = latest->transactions_per_second();
        snap.p50_ns = latest->p50_ns;
        snap.p99_ns = latest->p99_ns;
        snap.max_ns = latest->max_ns;
        snap.errors = latest->errors;
        snap.total_transactions = total_transactions_;
        snap.open_connections = open_now();
        options_.on_progress(snap);
    }

    const Plan& plan_;
    const EngineOptions& options_;
    const StageSchedule& schedule_;
    const RunWindow window_;
    const std::chrono::system_clock::time_point measure_start_wall_;
    stats::IntervalTimeline& timeline_;
    const std::function<std::uint32_t()> open_now_;  // connections open across the workers
    const std::size_t max_intervals_;
    std::function<void(const stats::IntervalHistograms&)> hand_over_;
    OutageWatch outages_;
    std::vector<std::uint32_t> open_by_interval_;  // open connections seen during each interval
    std::uint64_t reported_ = UINT64_MAX;
    std::uint64_t total_transactions_ = 0;
    std::size_t streamed_ = 0;  // intervals handed to on_interval
    std::vector<stats::IntervalSummary> fresh_;
};

// The run's metadata: what was asked, what ran, and the notes every report shows.
void describe_run(const Plan& plan, const EngineOptions& options, const StageSchedule& schedule,
                  const RunSetup& setup, const RunClock& clock, std::int64_t finished_ns,
                  stats::RunMetadata& meta) {
    meta.tool_version = options.tool_version;
    meta.target = setup.endpoint.to_string();
    meta.threads = setup.threads;
    meta.connections = setup.capacity;
    meta.depth = plan.depth;
    meta.model =
        plan.model == LoadModel::OpenLoop ? stats::LoadModel::Open : stats::LoadModel::Closed;
    meta.rate_per_second = plan.model == LoadModel::OpenLoop ? schedule.peak_rate() : 0.0;
    meta.requested_duration_ns =
        static_cast<std::uint64_t>(schedule.empty() ? plan.duration.count() : schedule.total_ns());
    meta.measured_duration_ns =
        static_cast<std::uint64_t>(finished_ns - clock.window.measure_start_ns);
    meta.warmup_ns = static_cast<std::uint64_t>(plan.warmup.count());
    meta.start_time = clock.wall_start;
    if (plan.shard.count != 0) {
        meta.shard_index = plan.shard.index;
        meta.shard_count = plan.shard.count;
    }
    if (options.start_at) {
        meta.start_at_epoch_s =
            std::chrono::duration<double>(options.start_at->time_since_epoch()).count();
        meta.late_by_ns = clock.late_by_ns;
        if (clock.late_by_ns != 0) {
            meta.notes.push_back(
                fmt::format("started late: {:.3f}s after --start-at (epoch {:.3f}s); began at once",
                            static_cast<double>(clock.late_by_ns) / 1e9, meta.start_at_epoch_s));
        }
    }
    if (!plan.serial.device.empty()) {
        meta.backend = "serial";
    } else {
        meta.backend = std::string(net::backend_name(setup.backend.backend));
        if (!setup.backend.why.empty())
            meta.notes.push_back(fmt::format("backend: epoll; {}", setup.backend.why));
    }
    if (plan.model == LoadModel::OpenLoop) {
        meta.notes.push_back(
            "open loop: latency measured from each request's intended send time (coordinated "
            "omission corrected)");
    }
}

// Answers that could not be framed as Modbus/TCP: what they were, so that a target speaking
// another protocol is not a mystery of 100 % framing errors and "received 0 B".
void note_foreign_protocol(LoadResult& result) {
    if (result.framing_errors == 0 || result.unframed_bytes == 0) return;
    result.warnings.push_back(fmt::format(
        "{} connection{} received {} that could not be read as Modbus/TCP (framing_error; not "
        "counted as received): the target looks like {}",
        result.framing_errors, result.framing_errors == 1 ? "" : "s",
        result.unframed_bytes == 1 ? std::string("1 byte")
                                   : fmt::format("{} bytes", result.unframed_bytes),
        describe_foreign_bytes(result.unframed_sample)));
}

// What a serial run adds to the metadata: the line is the target, one request at a time.
void describe_serial_run(const Plan& plan, const StageSchedule& schedule, const SerialRunner& line,
                         LoadResult& result) {
    stats::RunMetadata& meta = result.run.metadata;
    meta.target = line.describe();
    meta.notes.push_back(fmt::format("serial line {}: one request at a time", meta.target));
    if (!schedule.empty() && schedule.peak_connections() > 1)
        meta.notes.push_back(
            "serial line: one master, so the stages' connection counts only start (above 0) "
            "or stop (0) it; their rates apply");
    if (line.bad_checks != 0)
        result.warnings.push_back(
            fmt::format("{} answer{} with a bad {} (counted as crc_error)", line.bad_checks,
                        line.bad_checks == 1 ? "" : "s",
                        plan.serial.framing == codec::Framing::Ascii ? "LRC" : "CRC"));
}

// How the run's timeline is cut: each interval's length and how many the run needs at most.
struct TimelineShape {
    std::int64_t interval_ns = 0;
    std::int64_t run_ns = 0;  // warm-up and measured time; 0 when the count ends the run
    std::size_t max_intervals = 0;
};

TimelineShape shape_timeline(const Plan& plan, const EngineOptions& options,
                             const StageSchedule& schedule) {
    TimelineShape shape;
    shape.interval_ns = std::max<std::int64_t>(options.progress_interval_ns, 1000);
    // The warm-up comes on top of the measured time, for flag runs and stages alike.
    const std::int64_t measured_ns = schedule.empty() ? plan.duration.count() : schedule.total_ns();
    shape.run_ns = measured_ns > 0 ? plan.warmup.count() + measured_ns : 0;
    shape.max_intervals =
        shape.run_ns > 0 ? static_cast<std::size_t>(shape.run_ns / shape.interval_ns) + 16 : 86400;
    return shape;
}

// One run once the plan is known to be able to run: its workers (rings over TCP, or the one
// master of a serial line), the threads they run on, the watch over them, and what they
// measured gathered and described.
class EngineRun {
  public:
    EngineRun(const Plan& plan, const EngineOptions& options, const StageSchedule& schedule,
              const RunSetup& setup)
        : plan_(plan),
          options_(options),
          schedule_(schedule),
          setup_(setup),
          shape_(shape_timeline(plan, options, schedule)),
          timeline_(static_cast<std::uint64_t>(shape_.interval_ns), setup.threads,
                    shape_.max_intervals),
          clock_(start_clock(plan, options, shape_.run_ns)) {
        if (options.on_interval_histograms)
            timeline_.keep_histograms(static_cast<std::uint32_t>(plan.operations.size()));
    }

    // Makes the workers (opens the serial line): an error when the line cannot be opened.
    Error start() {
        if (options_.live != nullptr) {
            options_.live->prepare(plan_, setup_.threads);
            options_.live->set_running(true);
        }
        if (plan_.serial.device.empty()) {
            workers_ = make_workers(plan_, setup_.endpoint, setup_.sources, setup_.threads,
                                    setup_.capacity, clock_.window, schedule_,
                                    WorkerLinks{options_, abort_, any_connected_, timeline_,
                                                setup_.direct, setup_.backend.backend});
            return {};
        }
        line_ = std::make_unique<SerialRunner>(SerialRunSetup{
            &plan_, &options_, &schedule_, &timeline_,
            options_.live != nullptr ? options_.live->worker(0) : nullptr, clock_.window.start_ns,
            clock_.window.measure_start_ns, clock_.window.end_ns, &abort_});
        Error opened = line_->open();
        if (!opened.ok() && options_.live != nullptr) options_.live->set_running(false);
        return opened;
    }

    // Runs the workers on their threads, watching them every 10 ms, until all are done.
    void drive() {
        std::atomic<std::uint32_t> finished{0};
        std::vector<std::thread> pool;
        pool.reserve(setup_.threads);
        if (line_) {
            pool.emplace_back([&finished, line = line_.get()] {
                line->run();
                finished.fetch_add(1);
            });
        }
        for (auto& w : workers_) {
            pool.emplace_back([&finished, worker = w.get()] {
                worker->run();
                finished.fetch_add(1);
            });
        }
        watch_.emplace(
            plan_, options_, schedule_, clock_, timeline_, [this] { return open_connections(); },
            shape_.max_intervals);
        while (finished.load() < setup_.threads) {
            std::this_thread::sleep_for(std::chrono::milliseconds(10));
            watch_->look(abort_.load() ||
                         (options_.stop && options_.stop->load(std::memory_order_relaxed)));
        }
        for (auto& t : pool) t.join();
        if (options_.live != nullptr) options_.live->set_running(false);
        timeline_.finish();
        watch_->drain_histograms();
    }

    // What the workers measured, and the first error that ended the run early.
    void gather(LoadResult& result) {
        describe_stages(plan_, schedule_, result.run.stages);
        finished_ns_ = clock_.window.measure_start_ns;
        if (line_) {
            take_serial_results(*line_, result);
            finished_ns_ = std::max(finished_ns_, line_->finished_ns);
        } else {
            merge_results(plan_, workers_, result);
        }
        for (auto& w : workers_) {
            finished_ns_ = std::max(finished_ns_, w->finished_ns);
            if (result.error.ok() && !w->fatal_error.ok()) result.error = w->fatal_error;
        }
        if (result.error.ok() && !line_ && !any_connected_.load())
            result.error = no_connection_error(
                plan_, setup_.endpoint,
                static_cast<double>(finished_ns_ - clock_.window.start_ns) / 1e9);
    }

    // The metadata, timeline, stages and notes every report shows.
    void describe(LoadResult& result) {
        stats::RunMetadata& meta = result.run.metadata;
        describe_run(plan_, options_, schedule_, setup_, clock_, finished_ns_, meta);
        if (line_) describe_serial_run(plan_, schedule_, *line_, result);
        if (plan_.tls) meta.notes.push_back(net::describe_tls_path());
        result.run.timeline = timeline_.summaries();
        result.run.timeline_interval_ns = static_cast<std::uint64_t>(shape_.interval_ns);
        auto& series = result.run.timeline;
        fit_timeline_to_run(series, meta.measured_duration_ns, shape_.interval_ns);
        for (auto& iv : series) watch_->complete_interval(iv);
        watch_->stream_the_rest(series);
        place_stages(schedule_, meta.measured_duration_ns, result.run.stages);
        note_outages(watch_->outages(), clock_.window.measure_start_ns, result);
        if (!schedule_.empty()) {
            meta.notes.push_back(fmt::format(
                "stages: {} stage{}, rate and connections changed live (connections stay open)",
                schedule_.stages(), schedule_.stages() == 1 ? "" : "s"));
        }
        note_shortfalls(plan_, schedule_, options_.stop != nullptr && options_.stop->load(),
                        result.run);
        if (!setup_.verdict.write_operations.empty()) {
            result.warnings.push_back(
                fmt::format("write operations sent to {}: {}", meta.target,
                            fmt::join(setup_.verdict.write_operations, ", ")));
        }
        note_foreign_protocol(result);
    }

  private:
    // Connections open across the workers (the serial line counts as one while open).
    std::uint32_t open_connections() const {
        if (line_) return line_->open_connections();
        std::uint32_t open = 0;
        for (auto& w : workers_) open += w->open_connections.load(std::memory_order_relaxed);
        return open;
    }

    const Plan& plan_;
    const EngineOptions& options_;
    const StageSchedule& schedule_;
    const RunSetup& setup_;
    const TimelineShape shape_;
    stats::IntervalTimeline timeline_;
    const RunClock clock_;
    std::atomic<bool> abort_{false};
    std::atomic<bool> any_connected_{false};
    std::vector<std::unique_ptr<Worker>> workers_;
    std::unique_ptr<SerialRunner> line_;
    std::optional<RunWatch> watch_;
    std::int64_t finished_ns_ = 0;
};

}  // namespace

LoadResult run_load(const Plan& plan, const EngineOptions& options) {
    LoadResult result;
    if (result.error = validate_plan(plan); !result.error.ok()) {
        result.error.prefixed("invalid plan");
        return result;
    }
    const StageSchedule schedule(plan);
    RunSetup setup;
    result.error = plan.serial.device.empty() ? prepare_run(plan, options, schedule, setup)
                                              : prepare_serial_run(plan, setup);
    if (!result.error.ok()) return result;
    EngineRun run(plan, options, schedule, setup);
    if (result.error = run.start(); !result.error.ok()) return result;
    run.drive();
    run.gather(result);
    run.describe(result);
    return result;
}

}  // namespace mbstorm::load
