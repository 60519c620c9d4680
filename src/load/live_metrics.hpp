// Live totals of a running load test for `run --metrics-listen`: each worker thread writes
// its own cells (relaxed atomics, one writer each: a load and a store, no locked
// read-modify-write, no allocation), and any thread may take a snapshot while it runs.
// The cells outlive the run, so the last snapshot holds the final totals.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "load/plan.hpp"
#include "stats/counters.hpp"
#include "stats/latency_buckets.hpp"
#include "stats/live_metrics.hpp"

namespace mbstorm::load {

// A counter or gauge with one writing thread; readable from any thread.
class LiveCell {
  public:
    void add(std::uint64_t n = 1) noexcept {
        value_.store(value_.load(std::memory_order_relaxed) + n, std::memory_order_relaxed);
    }
    void set(std::uint64_t v) noexcept { value_.store(v, std::memory_order_relaxed); }
    std::uint64_t get() const noexcept { return value_.load(std::memory_order_relaxed); }

  private:
    std::atomic<std::uint64_t> value_{0};
};

struct LiveOperationCells {
    std::array<LiveCell, stats::kOutcomeCount> outcomes;
    std::array<LiveCell, 256> exceptions;  // by exception code byte
    LiveCell sent, bytes_sent, bytes_received;
    std::array<LiveCell, stats::kLatencyBuckets> latency_buckets;
    LiveCell latency_sum_ns;
};

// One worker's cells. Only measured transactions (after warm-up) are counted, as in the report.
struct LiveWorkerCells {
    explicit LiveWorkerCells(std::size_t operations)
        : operations(std::make_unique<LiveOperationCells[]>(operations)) {}

    void record(std::uint32_t op, stats::Outcome outcome, std::uint8_t exception_code,
                bool answered, std::uint64_t latency_ns) noexcept {
        LiveOperationCells& cells = operations[op];
        cells.outcomes[static_cast<std::size_t>(outcome)].add();
        if (outcome == stats::Outcome::Exception) cells.exceptions[exception_code].add();
        if (answered) {
            cells.latency_buckets[stats::latency_bucket(latency_ns)].add();
            cells.latency_sum_ns.add(latency_ns);
        }
    }

    std::unique_ptr<LiveOperationCells[]> operations;
    std::array<LiveCell, stats::kOutcomeCount> stray;  // UnknownId / DuplicateId
    LiveCell stray_bytes;
    LiveCell connections_opened, connections_failed, connections_closed_by_peer;
    LiveCell open_connections, in_flight;  // gauges
    LiveCell tls_handshakes, tls_resumed, tls_handshake_failures, tls_handshake_ns;
    LiveCell tls_offloaded, tls_offload_errors;
};

class LiveMetrics {
  public:
    // `shard`: "I" for shard I of a distributed run (the `shard` label), empty otherwise.
    explicit LiveMetrics(std::string test_id = {}, std::string shard = {})
        : test_id_(std::move(test_id)), shard_(std::move(shard)) {}

    // The engine, before its workers start: one set of cells per worker thread.
    void prepare(const Plan& plan, std::uint32_t threads);
    LiveWorkerCells* worker(std::uint32_t index) noexcept;
    // The engine's own thread, while the run goes.
    void set_rates(double target, double achieved) noexcept;
    void set_running(bool running) noexcept { running_.store(running, std::memory_order_relaxed); }

    // Any thread, at any time (locks out only prepare(), never a worker).
    stats::LiveLoad snapshot() const;

  private:
    std::string test_id_;
    std::string shard_;
    mutable std::mutex mutex_;
    std::vector<stats::LiveOperation> labels_;  // name, function and unit of each operation
    std::vector<std::unique_ptr<LiveWorkerCells>> workers_;
    std::atomic<double> target_rate_{0};
    std::atomic<double> achieved_rate_{0};
    std::atomic<bool> running_{false};
};

}  // namespace mbstorm::load
