// Everything a finished run hands to the reports (console, JSON, .hgrm, HTML).
// Filled by the load engine (and later the scenario layer); read-only for report/.
// All durations and offsets are nanoseconds; offsets are measured from the run start
// (the end of warm-up: warm-up samples are not in any histogram).
#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "stats/counters.hpp"
#include "stats/histogram.hpp"
#include "stats/interval_recorder.hpp"

namespace mbstorm::stats {

enum class LoadModel : std::uint8_t {
    Closed,  // each connection keeps `depth` requests in flight, sends as answers arrive
    Open,    // requests are sent on a fixed schedule (`rate_per_second`) whatever the latency
};
constexpr const char* load_model_name(LoadModel model) noexcept {
    return model == LoadModel::Open ? "open" : "closed";
}

struct RunMetadata {
    std::string tool_version;  // e.g. "mbstorm 0.1.0"
    std::string target;        // "host:port"
    std::uint32_t threads = 0;
    std::string backend;            // "io_uring", "epoll" or "serial" (empty: not recorded)
    std::uint32_t connections = 0;  // total across threads
    std::uint32_t depth = 0;        // requests in flight per connection (closed loop)
    LoadModel model = LoadModel::Closed;
    double rate_per_second = 0.0;             // open loop target rate (0 for closed)
    std::uint64_t requested_duration_ns = 0;  // what the user asked for
    std::uint64_t measured_duration_ns = 0;   // what was measured (throughput divides by this)
    std::uint64_t warmup_ns = 0;
    std::chrono::system_clock::time_point start_time{};  // wall clock at run start
    bool coordinated_omission_corrected = false;         // closed loop histograms back-filled
    std::vector<std::string> notes;                      // e.g. "embedded slave on 127.0.0.1:15020"
    // Which test the run belongs to, for `mbstorm merge`: the user's --test-id (may be empty)
    // and a random id of this run (its interval log carries it too).
    std::string test_id;
    std::string run_id;
    // Runs merged into this result (mbstorm merge); 0 for a single run.
    std::uint32_t merged_runs = 0;
    // run --shard I/N: this run is shard I (0-based) of N; count 0 when not sharded.
    std::uint32_t shard_index = 0;
    std::uint32_t shard_count = 0;
    // run --start-at: the wall-clock time asked for (seconds since the epoch; 0: none) and how
    // late the run started against it (0 when on time).
    double start_at_epoch_s = 0.0;
    std::uint64_t late_by_ns = 0;
};

struct OperationResult {
    std::string name;                // e.g. "read_holding_registers" or a scenario label
    std::uint8_t function_code = 0;  // Modbus function code
    Histogram latency;
    OutcomeCounters counters;
};

// One scenario stage; the whole-run data is the sum over stages.
struct StageResult {
    std::string name;
    std::uint32_t index = 0;
    std::uint64_t start_offset_ns = 0;
    std::uint64_t end_offset_ns = 0;
    Histogram latency;
    OutcomeCounters counters;
    std::vector<OperationResult> operations;  // optional per-stage, per-operation breakdown
    // The schedule the stage asked for, at its start and its end (equal unless it ramps):
    // open-loop rate (0 in a closed loop) and connections, both over all threads.
    double rate_from = 0.0;
    double rate_to = 0.0;
    std::uint32_t connections_from = 0;
    std::uint32_t connections_to = 0;
};

// Sends that went out later than their slot + tolerance.
struct LagCounts {
    std::uint64_t late_sends = 0;
    std::uint64_t max_lag_ns = 0;
    std::uint64_t total_lag_ns = 0;  // sum over late sends (mean = total / late_sends)

    void add(const LagCounts& other) noexcept {
        late_sends += other.late_sends;
        total_lag_ns += other.total_lag_ns;
        max_lag_ns = other.max_lag_ns > max_lag_ns ? other.max_lag_ns : max_lag_ns;
    }
    double mean_lag_ns() const noexcept {
        return late_sends == 0
                   ? 0.0
                   : static_cast<double>(total_lag_ns) / static_cast<double>(late_sends);
    }
};

// Open loop only: how often a send missed its slot, and why. Two causes look alike from the
// schedule alone and call for opposite remedies, so they are counted apart.
struct ScheduleLag {
    // The engine itself was late (its CPU, scheduling): a connection had room to send.
    LagCounts engine;
    // The target was not keeping up: every open connection had its in-flight window full
    // (depth requests waiting for answers), or none was open, so the send waited.
    LagCounts target;

    LagCounts total() const noexcept {
        LagCounts all = engine;
        all.add(target);
        return all;
    }
};

struct ConnectionStats {
    std::uint64_t opened = 0;      // successful connects
    std::uint64_t failed = 0;      // connect attempts that failed
    std::uint64_t reconnects = 0;  // connects after a connection was lost
    std::uint64_t closed_by_peer = 0;
    std::uint64_t peak_open = 0;  // most open at once (summed over threads' own peaks)
    // --transport tls: handshakes completed, how many resumed a session, and their latency
    // (TCP connect done to handshake done).
    std::uint64_t tls_handshakes = 0;
    std::uint64_t tls_resumed = 0;
    std::uint64_t tls_handshake_ns_total = 0;
    std::uint64_t tls_handshake_ns_max = 0;
    // Connects that ended at the handshake: refused, malformed or past the connect timeout
    // (counted in `failed` too).
    std::uint64_t tls_handshake_failures = 0;
    // Of the handshakes, connections handed to the kernel's TLS (the rest stayed in userspace
    // OpenSSL), and offloaded connections ended by a record the kernel does not pass as data
    // (close_notify, an alert, a TLS 1.3 KeyUpdate) or by a hand-off that failed half-way.
    std::uint64_t tls_offloaded = 0;
    std::uint64_t tls_offload_errors = 0;
    // `failed` by cause: the errno's name ("ECONNREFUSED", "EADDRNOTAVAIL"; "ETIMEDOUT" for a
    // connect that outlived the connect timeout, "EPROTO" for a failed TLS handshake).
    std::map<std::string, std::uint64_t> failed_by_cause;
};

// A part of the plan the run could not carry out: every report says so, and thresholds
// judged on such a run fail (see scenario/threshold.hpp).
struct PlanShortfall {
    std::string what;  // "connections", "rate" or "duration"
    double planned = 0.0;
    double achieved = 0.0;
    std::string text;  // e.g. "connections: 9,326 of 10,000 opened (674 connect attempts failed)"
};

// Hints that pipelining hurt: a target that answers one request at a time loses the requests
// queued behind the first, and they time out.
struct PipeliningSigns {
    // Requests that timed out although a request sent after them on the same connection was
    // answered: the target skipped them.
    std::uint64_t skipped_requests = 0;
};

// A pass/fail check, e.g. "p99 < 5ms"; filled by the scenario layer.
struct ThresholdResult {
    std::string expression;
    double observed = 0.0;
    std::string observed_text;  // observed value formatted with its unit, e.g. "3.2ms"
    bool passed = false;
};

struct RunResult {
    RunMetadata metadata;
    Histogram latency;  // all operations
    // Open loop: the same answers timed from their actual send, not their intended one (wrk2's
    // --u_latency): the target's service time, without the queueing the schedule saw. Empty
    // in closed loop, where the two are one.
    Histogram service_time;
    OutcomeCounters counters;  // all operations
    std::vector<OperationResult> operations;
    std::vector<IntervalSummary> timeline;  // from IntervalTimeline::summaries()
    std::uint64_t timeline_interval_ns = 1'000'000'000;
    std::vector<StageResult> stages;  // empty unless a scenario had stages
    ScheduleLag schedule_lag;
    ConnectionStats connections;
    std::vector<PlanShortfall> shortfalls;  // empty when the plan was carried out
    PipeliningSigns pipelining;
    std::vector<ThresholdResult> thresholds;

    // Completed transactions per second over the measured duration.
    double throughput() const noexcept {
        return metadata.measured_duration_ns == 0
                   ? 0.0
                   : static_cast<double>(counters.completed()) * 1e9 /
                         static_cast<double>(metadata.measured_duration_ns);
    }
    bool thresholds_passed() const noexcept {
        for (const auto& t : thresholds)
            if (!t.passed) return false;
        return true;
    }
};

}  // namespace mbstorm::stats
