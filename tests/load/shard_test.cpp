#include "load/shard.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "load/operation_generator.hpp"
#include "load/stage_schedule.hpp"

namespace mbstorm::load {
namespace {

Plan open_plan() {
    Plan p;
    p.operations.push_back({});
    p.operations[0].first_address = 0;
    p.operations[0].last_address = 99;
    p.operations[0].quantity = 10;
    p.model = LoadModel::OpenLoop;
    p.connections = 10;
    p.rate = 1000;
    p.transactions = 10001;
    return p;
}

std::vector<Plan> shards_of(const Plan& p, std::uint32_t n) {
    std::vector<Plan> out;
    for (std::uint32_t i = 0; i < n; ++i) {
        Result<Plan> s = shard_plan(p, i, n);
        EXPECT_TRUE(s.ok()) << s.error() << " shard " << i;
        if (!s.ok()) continue;
        EXPECT_TRUE(validate_plan(*s).ok()) << "shard " << i;
        out.push_back(std::move(s).value());
    }
    return out;
}

TEST(Shard, CountsSplitLikeThreadsWithTheRemainderOnTheLowestShards) {
    const auto parts = shards_of(open_plan(), 3);
    EXPECT_EQ(parts[0].connections, 4u);
    EXPECT_EQ(parts[1].connections, 3u);
    EXPECT_EQ(parts[2].connections, 3u);
    EXPECT_EQ(parts[0].transactions, 3334u);
    EXPECT_EQ(parts[1].transactions, 3334u);
    EXPECT_EQ(parts[2].transactions, 3333u);
    EXPECT_DOUBLE_EQ(parts[0].rate, 400.0);
    EXPECT_DOUBLE_EQ(parts[1].rate, 300.0);
    for (std::uint32_t i = 0; i < 3; ++i) {
        EXPECT_EQ(parts[i].shard.index, i);
        EXPECT_EQ(parts[i].shard.count, 3u);
    }
}

TEST(Shard, SumsOverShardsAreTheWholePlanForEveryCountAndStage) {
    Plan p = open_plan();
    p.transactions = 0;
    p.connections = 7;
    p.rate = 0;  // a ramp up from nothing
    p.stages = {{std::chrono::seconds(2), 700.0, 13u, Ramp::Linear, "up"},
                {std::chrono::seconds(2), std::nullopt, 3u, Ramp::Constant, "fewer, same rate"},
                {std::chrono::seconds(2), 0.0, 0u, Ramp::Linear, "down"},
                {std::chrono::seconds(1), 50.0, std::nullopt, Ramp::Constant, "restart"}};
    p.stages[3].target_connections = 5;
    for (std::uint32_t n : {1u, 2u, 3u}) {
        const auto parts = shards_of(p, n);
        std::uint32_t connections = 0;
        double rate = 0;
        for (const auto& s : parts) {
            connections += s.connections;
            rate += s.rate;
        }
        EXPECT_EQ(connections, p.connections) << n << " shards";
        EXPECT_DOUBLE_EQ(rate, p.rate);
        // The schedules add up to the whole one at every stage end and in the middle of ramps.
        const StageSchedule whole(p);
        std::vector<StageSchedule> each;
        for (const auto& s : parts) each.emplace_back(s);
        for (std::int64_t t = -1; t <= whole.total_ns() + 1; t += 250'000'000) {
            double sum_rate = 0;
            std::uint32_t at_ends = 0;
            for (const auto& s : each) sum_rate += s.at(t).rate;
            EXPECT_NEAR(sum_rate, whole.at(t).rate, 1e-6) << n << " shards at " << t;
            for (std::size_t k = 0; k < whole.stages(); ++k) {
                at_ends = 0;
                for (const auto& s : each) at_ends += s.stage_to(k).connections;
                EXPECT_EQ(at_ends, whole.stage_to(k).connections) << "stage " << k;
            }
        }
        double scheduled = 0;
        for (const auto& s : each) scheduled += s.scheduled_transactions(whole.total_ns());
        EXPECT_NEAR(scheduled, whole.scheduled_transactions(whole.total_ns()), 1e-6);
    }
}

TEST(Shard, ShardsDrawApartButOneShardIsTheWholePlan) {
    Plan p = open_plan();
    p.operations[0].address_mode = AddressMode::Sequential;
    const Result<Plan> one = shard_plan(p, 0, 1);
    ASSERT_TRUE(one.ok()) << one.error();
    EXPECT_EQ(one->seed, p.seed);
    EXPECT_EQ(one->connections, p.connections);
    EXPECT_EQ(one->operations[0].start_offset, 0u);

    // Sequential: each shard starts at its own block; together they start spread over the
    // range (10 blocks of 10 addresses over 3 shards: 0, 30, 60).
    const auto parts = shards_of(p, 3);
    std::set<std::uint16_t> firsts;
    std::set<std::uint64_t> seeds;
    for (const auto& s : parts) {
        OperationGenerator g(s.operations, s.seed);
        std::uint8_t buffer[300];
        RequestInfo info;
        ASSERT_NE(g.next(1, codec::MutableBytes(buffer, sizeof buffer), info), 0u);
        firsts.insert(info.address);
        seeds.insert(s.seed);
    }
    EXPECT_EQ(firsts, (std::set<std::uint16_t>{0, 30, 60}));
    EXPECT_EQ(seeds.size(), 3u);
}

TEST(Shard, AShardWithNothingToDoIsRefusedSayingWhy) {
    Plan p = open_plan();
    p.connections = 2;
    EXPECT_EQ(shard_plan(p, 2, 3).error().message(),
              "shard 2/3 gets 0 of the plan's 2 connections: every shard needs one (use at most 2 "
              "shards)");
    p.connections = 10;
    p.transactions = 2;
    EXPECT_EQ(shard_plan(p, 2, 3).error().message(),
              "shard 2/3 gets 0 of the plan's 2 transactions: every shard needs one (use at most "
              "2 shards)");
    EXPECT_EQ(shard_plan(p, 3, 3).error().message(),
              "shard index 3 is out of range for 3 shards (valid 0..2)");
    EXPECT_EQ(shard_plan(p, 0, 0).error().message(),
              "shard count 0 is out of range (valid 1..100000)");
    EXPECT_EQ(shard_plan(p, 0, 0).error().code(), ErrorCode::InvalidInput);
}

}  // namespace
}  // namespace mbstorm::load
