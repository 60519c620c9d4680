// A consistent-enough copy of a running load test's totals, for live metrics (Prometheus).
// Plain values: the engine fills it from its workers' atomics, report/ formats it.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "stats/counters.hpp"
#include "stats/latency_buckets.hpp"

namespace mbstorm::stats {

struct LiveOperation {
    std::string name;  // the operation's label (a scenario's name, or the function's)
    std::uint8_t function_code = 0;
    std::uint8_t unit_id = 0;
    OutcomeCounters counters;                                      // measured transactions only
    std::array<std::uint64_t, kLatencyBuckets> latency_buckets{};  // per bucket, not cumulative
    std::uint64_t latency_sum_ns = 0;
};

// --transport tls: zero on other transports.
struct LiveTls {
    std::uint64_t handshakes = 0;          // completed
    std::uint64_t resumed = 0;             // of them, sessions resumed
    std::uint64_t handshake_failures = 0;  // ended at the handshake (certificate, protocol, time)
    std::uint64_t handshake_ns_total = 0;  // TCP connect done to handshake done, summed
    std::uint64_t offloaded = 0;           // of the handshakes, handed to the kernel's TLS
    std::uint64_t offload_errors = 0;      // offloaded connections ended by a non-data record
};

struct LiveLoad {
    std::string test_id;  // --test-id; empty when not given
    std::string shard;    // run --shard I/N: "I"; empty for a whole run
    std::vector<LiveOperation> operations;
    OutcomeCounters stray;  // responses that answered no transaction
    std::uint64_t connections_opened = 0;
    std::uint64_t connections_failed = 0;
    std::uint64_t connections_closed_by_peer = 0;
    std::uint64_t open_connections = 0;
    std::uint64_t in_flight = 0;  // requests sent and not yet answered or timed out
    double target_rate = 0;       // open loop: transactions per second asked for now
    double achieved_rate = 0;     // transactions per second over the last full interval
    bool running = false;         // false before the run starts and once it ended
    LiveTls tls;
};

}  // namespace mbstorm::stats
