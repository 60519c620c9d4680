#include "load/plan.hpp"
#include "load/thread_share.hpp"

#include <gtest/gtest.h>

#include <string>

namespace mbstorm::load {
namespace {

Plan valid_plan() {
    Plan plan;
    Operation op;
    op.name = "read";
    op.function = 0x03;
    op.first_address = 0;
    op.last_address = 99;
    op.quantity = 10;
    plan.operations.push_back(op);
    return plan;
}

bool any_contains(const Error& error, const std::string& needle) {
    return error.message().find(needle) != std::string::npos;
}

TEST(PlanValidation, DefaultPlanWithOneOperationIsValid) {
    EXPECT_TRUE(validate_plan(valid_plan()).ok());
}

TEST(PlanValidation, EveryProblemIsNamedInOneError) {
    Plan plan = valid_plan();
    plan.connections = 0;
    plan.depth = 0;
    EXPECT_EQ(validate_plan(plan).message(),
              "connections: 0 is out of range (valid 1..100000); depth: 0 is out of range (valid "
              "1..32768)");
}

TEST(PlanValidation, ConnectionsOutOfRangeNamesTheRange) {
    Plan plan = valid_plan();
    plan.connections = 0;
    const Error error = validate_plan(plan);
    EXPECT_EQ(error.code(), ErrorCode::InvalidInput);
    EXPECT_EQ(error.message(), "connections: 0 is out of range (valid 1..100000)");
    plan.connections = 100001;
    EXPECT_TRUE(any_contains(validate_plan(plan), "valid 1..100000"));
    plan.connections = 100000;
    EXPECT_TRUE(validate_plan(plan).ok());
}

TEST(PlanValidation, DepthAndThreads) {
    Plan plan = valid_plan();
    plan.depth = 0;
    EXPECT_TRUE(any_contains(validate_plan(plan), "depth: 0 is out of range (valid 1..32768)"));
    plan.depth = 32768;
    EXPECT_TRUE(validate_plan(plan).ok());
    plan.threads = 5000;
    EXPECT_TRUE(any_contains(validate_plan(plan), "threads"));
}

TEST(PlanValidation, OpenLoopNeedsARate) {
    Plan plan = valid_plan();
    plan.model = LoadModel::OpenLoop;
    EXPECT_TRUE(any_contains(validate_plan(plan), "rate"));
    plan.rate = 1000;
    EXPECT_TRUE(validate_plan(plan).ok());
}

TEST(PlanValidation, QuantityLimitsComeFromTheSpec) {
    Plan plan = valid_plan();
    plan.operations[0].quantity = 126;  // FC03 allows 1..125
    plan.operations[0].last_address = 1000;
    EXPECT_TRUE(any_contains(validate_plan(plan), "valid 1..125"));
    plan.operations[0].function = 0x01;  // FC01 allows 1..2000
    EXPECT_TRUE(validate_plan(plan).ok());
    plan.operations[0].quantity = 2001;
    plan.operations[0].last_address = 65535;
    EXPECT_TRUE(any_contains(validate_plan(plan), "valid 1..2000"));
    plan.operations[0].function = 0x10;
    plan.operations[0].quantity = 124;
    EXPECT_TRUE(any_contains(validate_plan(plan), "valid 1..123"));
}

TEST(PlanValidation, AddressRangeMustHoldTheBlock) {
    Plan plan = valid_plan();
    plan.operations[0].first_address = 95;  // 95..104 does not fit in [95, 99]
    EXPECT_TRUE(any_contains(validate_plan(plan), "cannot hold 10 items"));
    plan.operations[0].first_address = 65530;
    plan.operations[0].last_address.reset();
    EXPECT_TRUE(any_contains(validate_plan(plan), "runs past 65535"));
}

TEST(PlanValidation, UnsupportedFunctionZeroWeightBadZipfEmptyPattern) {
    Plan plan = valid_plan();
    plan.operations[0].function = 0x42;
    EXPECT_TRUE(any_contains(validate_plan(plan), "cannot be generated"));
    plan = valid_plan();
    plan.operations[0].weight = 0;
    EXPECT_TRUE(any_contains(validate_plan(plan), "weight"));
    plan = valid_plan();
    plan.operations[0].address_mode = AddressMode::Zipf;
    plan.operations[0].zipf_exponent = 0;
    EXPECT_TRUE(any_contains(validate_plan(plan), "zipf exponent"));
    plan = valid_plan();
    plan.operations[0].function = 0x10;
    plan.operations[0].values.mode = ValueMode::Pattern;
    EXPECT_TRUE(any_contains(validate_plan(plan), "pattern is empty"));
}

TEST(PlanValidation, DurationWarmupAndEmptyMix) {
    Plan plan = valid_plan();
    plan.duration = Duration::zero();
    EXPECT_TRUE(any_contains(validate_plan(plan), "never ends"));
    plan.transactions = 100;
    EXPECT_TRUE(validate_plan(plan).ok());
    plan = valid_plan();
    plan.warmup = plan.duration;  // comes on top of the duration: nothing is cut
    EXPECT_TRUE(validate_plan(plan).ok());
    plan.warmup = -plan.duration;
    EXPECT_TRUE(any_contains(validate_plan(plan), "warmup"));
    plan = valid_plan();
    plan.operations.clear();
    EXPECT_TRUE(any_contains(validate_plan(plan), "operations: none given"));
}

TEST(PlanValidation, StageTargetsAreCheckedAgainstTheModel) {
    Plan plan = valid_plan();
    Stage stage;
    stage.duration = std::chrono::seconds(1);
    stage.target_rate = 500;
    plan.stages.push_back(stage);
    EXPECT_TRUE(any_contains(validate_plan(plan), "stages[0]: a target rate needs an open-loop"));
    plan.model = LoadModel::OpenLoop;
    plan.rate = 0;  // a ramp up from nothing is fine when a stage has a rate
    EXPECT_TRUE(validate_plan(plan).ok());
    plan.stages[0].target_rate = 0;
    EXPECT_TRUE(any_contains(validate_plan(plan), "rate: 0 is out of range"));
    plan.stages[0].target_rate = 500;
    plan.stages[0].duration = Duration::zero();
    EXPECT_TRUE(any_contains(validate_plan(plan), "stages[0]: duration 0s is out of range"));
    plan.stages[0].duration = std::chrono::seconds(1);
    plan.stages[0].target_connections = kMaxConnections + 1;
    EXPECT_TRUE(any_contains(validate_plan(plan), "target connections 100001 is out of range"));
    plan.stages[0].target_connections = 0;  // closes every connection: allowed
    EXPECT_TRUE(validate_plan(plan).ok());
    plan.transactions = 5;
    EXPECT_TRUE(any_contains(validate_plan(plan), "transactions: not supported with stages"));
}

TEST(PlanValidation, LastStartAddressAndThreads) {
    Operation op;
    op.first_address = 10;
    op.last_address = 19;
    op.quantity = 4;
    EXPECT_EQ(last_start_address(op), 16);
    op.last_address.reset();
    EXPECT_EQ(last_start_address(op), 10);
    Plan plan = valid_plan();
    plan.threads = 8;
    plan.connections = 3;
    EXPECT_EQ(effective_threads(plan), 3u);
}

TEST(ThreadShare, SplitsEvenlyAndLosesNothing) {
    for (std::uint32_t threads : {1u, 2u, 3u, 7u}) {
        for (std::uint64_t total : {0ull, 1ull, 5ull, 64ull, 100001ull}) {
            std::uint64_t sum = 0;
            for (std::uint32_t i = 0; i < threads; ++i) {
                const std::uint64_t part = thread_share(total, threads, i);
                EXPECT_LE(part, total / threads + 1);
                EXPECT_GE(part, total / threads);
                sum += part;
            }
            EXPECT_EQ(sum, total) << total << " over " << threads;
        }
    }
    EXPECT_EQ(thread_share(5, 2, 0), 3u);  // the first threads take the remainder
    EXPECT_EQ(thread_share(5, 2, 1), 2u);
}

}  // namespace
}  // namespace mbstorm::load
