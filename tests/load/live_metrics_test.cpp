// --metrics-listen's live totals: read while the run goes, they only grow; after the run they
// are the report's numbers exactly.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>

#include "load/engine.hpp"
#include "load/live_metrics.hpp"
#include "server/server.hpp"

namespace mbstorm::load {
namespace {

using namespace std::chrono_literals;

Plan two_operation_plan(std::uint16_t port) {
    Plan plan;
    plan.host = "127.0.0.1";
    plan.port = port;
    Operation read;
    read.name = "read";
    read.function = 0x03;
    read.last_address = 99;
    read.quantity = 2;
    read.unit_id = 7;
    Operation other;  // the slave answers only unit 7: exception 0B (gateway) for this one
    other.name = "other_unit";
    other.function = 0x04;
    other.quantity = 2;
    other.unit_id = 9;
    plan.operations = {read, other};
    plan.threads = 2;
    plan.connections = 2;
    plan.depth = 2;
    plan.warmup = 200ms;
    plan.duration = 0s;
    plan.transactions = 4000;
    return plan;
}

TEST(LiveMetrics, EndsEqualToTheReportAndOnlyGrowsMeanwhile) {
    server::ServerConfig config;
    config.listen = "127.0.0.1:0";
    config.threads = 1;
    config.only_unit = 7;
    config.foreign_unit = server::ForeignUnitPolicy::GatewayException;
    server::Server slave(config);
    const Error error = slave.start();
    ASSERT_TRUE(error.ok()) << error.text();
    const Plan plan = two_operation_plan(slave.port());

    LiveMetrics live("soak-1");
    EngineOptions options;
    options.live = &live;
    std::atomic<bool> done{false};
    std::uint64_t snapshots = 0;
    bool monotone = true;
    std::thread reader([&] {
        std::uint64_t last_sent = 0;
        // Bounded: at most 30 s of snapshots, whatever happens to the run.
        for (int i = 0; i < 30'000 && !done.load(); ++i) {
            const stats::LiveLoad s = live.snapshot();
            std::uint64_t sent = 0;
            for (const auto& op : s.operations) sent += op.counters.transactions_sent;
            monotone = monotone && sent >= last_sent;
            last_sent = sent;
            ++snapshots;
            std::this_thread::sleep_for(1ms);
        }
    });
    const LoadResult r = run_load(plan, options);
    done = true;
    reader.join();
    ASSERT_TRUE(r.ok()) << r.error;
    EXPECT_GT(snapshots, 0u);
    EXPECT_TRUE(monotone);

    const stats::LiveLoad s = live.snapshot();
    EXPECT_FALSE(s.running);
    EXPECT_EQ(s.test_id, "soak-1");
    ASSERT_EQ(s.operations.size(), 2u);
    EXPECT_EQ(s.operations[0].name, "read");
    EXPECT_EQ(s.operations[0].function_code, 0x03);
    EXPECT_EQ(s.operations[0].unit_id, 7);
    std::uint64_t answered = 0;
    for (std::size_t op = 0; op < 2; ++op) {
        const auto& want = r.run.operations[op].counters;
        const auto& got = s.operations[op].counters;
        EXPECT_EQ(got.outcomes, want.outcomes) << op;
        EXPECT_EQ(got.exceptions, want.exceptions) << op;
        EXPECT_EQ(got.transactions_sent, want.transactions_sent) << op;
        EXPECT_EQ(got.bytes_sent, want.bytes_sent) << op;
        EXPECT_EQ(got.bytes_received, want.bytes_received) << op;
        std::uint64_t in_buckets = 0;
        for (const auto n : s.operations[op].latency_buckets) in_buckets += n;
        EXPECT_EQ(in_buckets, r.run.operations[op].latency.total_count()) << op;
        answered += in_buckets;
    }
    EXPECT_GT(s.operations[1].counters.exceptions[0x0B], 0u);
    EXPECT_EQ(
        s.operations[0].counters.transactions_sent + s.operations[1].counters.transactions_sent,
        4000u);
    EXPECT_GT(answered, 0u);
    // Each answer's latency, recorded once into its operation's interval histogram, reaches
    // the operation's run-long histogram and the timeline exactly once.
    std::uint64_t in_intervals = 0;
    for (const auto& interval : r.run.timeline) in_intervals += interval.latency_count;
    EXPECT_EQ(in_intervals, answered);
    EXPECT_EQ(r.run.latency.total_count(), answered);
    for (std::size_t op = 0; op < 2; ++op) {
        const auto& c = r.run.operations[op].counters;
        EXPECT_EQ(r.run.operations[op].latency.total_count(),
                  c.ok() + c.count(stats::Outcome::Exception))
            << op;
    }
    EXPECT_EQ(s.connections_opened, r.run.connections.opened);
    EXPECT_EQ(s.connections_failed, r.run.connections.failed);
    EXPECT_EQ(s.in_flight, 0u);
}

TEST(LiveMetrics, LatencyBucketsHoldEachValueAtOrBelowTheirBound) {
    EXPECT_EQ(stats::latency_bucket(0), 0u);
    EXPECT_EQ(stats::latency_bucket(25'000), 0u);
    EXPECT_EQ(stats::latency_bucket(25'001), 1u);
    EXPECT_EQ(stats::latency_bucket(10'000'000'000), stats::kLatencyBuckets - 2);
    EXPECT_EQ(stats::latency_bucket(10'000'000'001), stats::kLatencyBuckets - 1);
    for (std::size_t i = 1; i < stats::kLatencyBucketBoundsNs.size(); ++i)
        EXPECT_LT(stats::kLatencyBucketBoundsNs[i - 1], stats::kLatencyBucketBoundsNs[i]);
}

}  // namespace
}  // namespace mbstorm::load
