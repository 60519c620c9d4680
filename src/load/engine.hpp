// The load engine behind `mbstorm run`: one io_uring ring per thread, each thread owning its
// connections, generator, pacer and histograms (no locks, no allocation on the hot path).
// run_load() blocks until the run ends (duration, transaction count, stop flag or a fatal
// error) and always returns whatever was measured.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "codec/pdu.hpp"
#include "load/live_metrics.hpp"
#include "load/plan.hpp"
#include "load/request_info.hpp"
#include "net/backend.hpp"
#include "stats/run_result.hpp"
#include "util/error.hpp"

namespace mbstorm::load {

// Once-per-interval view for the live progress line (called on run_load()'s thread).
struct ProgressSnapshot {
    std::uint64_t interval_index = 0;  // seconds since the end of warm-up
    double elapsed_seconds = 0;        // since the run started (warm-up included)
    double transactions_per_second = 0;
    std::uint64_t p50_ns = 0;
    std::uint64_t p99_ns = 0;
    std::uint64_t max_ns = 0;
    std::uint64_t errors = 0;  // in this interval
    std::uint64_t total_transactions = 0;
    std::uint32_t open_connections = 0;
};
using ProgressCallback = std::function<void(const ProgressSnapshot&)>;

// Every interval's full latency histograms (all operations, then one per plan operation), in
// order, as soon as every worker is past it (called on run_load()'s thread, never a worker's).
// measure_start: wall-clock time of interval offset 0 (the end of warm-up).
using IntervalHistogramsCallback =
    std::function<void(const stats::IntervalHistograms& interval,
                       std::chrono::system_clock::time_point measure_start)>;

// Optional content check of successful responses (e.g. read-back of known register values).
// Returns false on a mismatch, which is counted as Outcome::ValueMismatch. Called on worker
// threads, concurrently: it must be thread-safe and must not allocate.
// Every interval's summary (as the report's timeline has it), in order, once it is whole
// (called on run_load()'s thread). The run's last intervals come after the run, as the
// report fits them to its end. measure_start: wall-clock time of interval offset 0.
using IntervalCallback = std::function<void(const stats::IntervalSummary& interval,
                                            std::chrono::system_clock::time_point measure_start)>;

struct ResponseVerifier {
    bool (*check)(void* context, const RequestInfo& request,
                  const codec::Response& response) = nullptr;
    void* context = nullptr;
};

struct EngineOptions {
    ProgressCallback on_progress;
    const std::atomic<bool>* stop = nullptr;  // set it (e.g. on Ctrl-C) to end the run early
    ResponseVerifier verifier;
    std::string tool_version = "mbstorm";
    std::int64_t progress_interval_ns = 1'000'000'000;
    IntervalHistogramsCallback on_interval_histograms;  // optional: costs a histogram per operation
    // Hold sockets as io_uring direct descriptors when the kernel has them, so the open-files
    // limit does not cap the connections (false: plain descriptors, as on older kernels).
    bool use_direct_descriptors = true;
    // io_uring, epoll, or io_uring where the process may use it and epoll elsewhere.
    net::BackendChoice backend = net::BackendChoice::Auto;
    // Optional: live totals for --metrics-listen (prepared here, kept by the caller).
    LiveMetrics* live = nullptr;
    IntervalCallback on_interval;  // optional: --timeline
    // run --start-at: connect at once, send the first request (warm-up included) at this
    // wall-clock time; already past, start at once and record by how much (metadata.late_by_ns).
    std::optional<std::chrono::system_clock::time_point> start_at;
};

struct LoadResult {
    // Why the run could not start or ended early ("cannot connect to 10.0.0.9:502: Connection
    // refused"); what it measured until then is below either way.
    Error error;
    bool ok() const noexcept { return error.ok(); }
    std::vector<std::string> warnings;
    stats::RunResult run;
    // Accounting: run.counters.transactions_sent == run.counters.completed() + pending_at_end
    // (stray responses are counted apart: they answer no transaction).
    std::uint64_t pending_at_end = 0;  // sent but neither answered nor timed out at the end
    std::uint64_t late_responses = 0;  // answers that arrived after their transaction timed out
    std::uint64_t crc_errors = 0;      // RTU over TCP: answers whose CRC failed (connection reset)
    std::uint64_t framing_errors = 0;  // unrecoverable MBAP framing (connection was reset)
    // What those connections received that could not be framed: bytes, and the first bytes of
    // the first such receive (what the target speaks instead; see foreign_protocol.hpp).
    std::uint64_t unframed_bytes = 0;
    std::vector<std::uint8_t> unframed_sample;
    std::uint64_t bad_protocol_frames = 0;  // frames with protocol id != 0 (discarded)
    // The target went away during the run (no connection open for a while after one was) and
    // had not come back when it ended; each outage is also a note in run.metadata.notes.
    bool target_lost_at_end = false;
};

LoadResult run_load(const Plan& plan, const EngineOptions& options = {});

}  // namespace mbstorm::load
