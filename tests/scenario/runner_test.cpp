// Staged schedules, result merging, and end-to-end runs against the embedded reference slave.
// Every run here is bounded (well under 2 s of traffic) and loopback only.
#include <gtest/gtest.h>

#include "scenario/runner.hpp"
#include "scenario/scenario.hpp"

namespace mbstorm::scenario {
namespace {

using namespace std::chrono_literals;

TEST(StageSteps, LinearRampsBecomeStepsAtTheirMidpoints) {
    Scenario s = parse_scenario(R"(
rate: 100
stage_step: 1s
stages:
  - {duration: 2s, rate: 1100}
  - {duration: 3s, rate: 1100}
  - {duration: 1500ms, rate: 100, ramp: constant}
  - {duration: 1s, rate: 0}
operations: [{function: 3}]
)",
                                "s.yaml");
    const auto steps = plan_stage_steps(s);
    ASSERT_EQ(steps.size(), 5U);
    EXPECT_EQ(steps[0].stage, 0U);
    EXPECT_DOUBLE_EQ(steps[0].rate, 350);  // midpoint of 100 -> 1100 over the first second
    EXPECT_DOUBLE_EQ(steps[1].rate, 850);
    EXPECT_EQ(steps[0].duration, 1s);
    EXPECT_EQ(steps[2].stage, 1U);  // flat: one step for the whole stage
    EXPECT_EQ(steps[2].duration, 3s);
    EXPECT_DOUBLE_EQ(steps[3].rate, 100);  // constant
    EXPECT_EQ(steps[3].duration, 1500ms);
    EXPECT_DOUBLE_EQ(steps[4].rate, 50);  // ramp down 100 -> 0, one step
    EXPECT_EQ(steps[0].connections, kDefaultConnections);
}

TEST(StageSteps, ConnectionRampsRoundAndLastStepIsShort) {
    Scenario s = parse_scenario(R"(
connections: 1
stage_step: 400ms
stages: [{duration: 1s, connections: 11}]
operations: [{function: 3}]
)",
                                "c.yaml");
    const auto steps = plan_stage_steps(s);
    ASSERT_EQ(steps.size(), 3U);
    EXPECT_EQ(steps[0].connections, 3U);   // 1 + 10 * 0.2
    EXPECT_EQ(steps[1].connections, 7U);   // 1 + 10 * 0.6
    EXPECT_EQ(steps[2].connections, 10U);  // 1 + 10 * 0.9
    EXPECT_EQ(steps[2].duration, 200ms);
}

TEST(MergeStep, ShiftsTimelinesAndAddsIntoTheStage) {
    stats::RunResult step;
    step.metadata.measured_duration_ns = 1'000'000'000;
    step.latency.record(1000);
    step.counters.record(stats::Outcome::Ok);
    stats::IntervalSummary iv;
    iv.duration_ns = 1'000'000'000;
    iv.transactions = 1;
    step.timeline.push_back(iv);
    stats::OperationResult op;
    op.name = "r";
    op.latency.record(1000);
    op.counters.record(stats::Outcome::Ok);
    step.operations.push_back(op);
    op.name = "w";
    step.operations.push_back(op);

    stats::RunResult total;
    stats::StageResult stage;
    merge_step(total, step, &stage);
    merge_step(total, step, &stage);
    EXPECT_EQ(total.metadata.measured_duration_ns, 2'000'000'000U);
    ASSERT_EQ(total.timeline.size(), 2U);
    EXPECT_EQ(total.timeline[1].start_offset_ns, 1'000'000'000U);
    EXPECT_EQ(total.timeline[1].index, 1U);
    EXPECT_EQ(total.counters.ok(), 2U);
    EXPECT_EQ(stage.latency.total_count(), 2U);
    ASSERT_EQ(total.operations.size(), 2U);
    EXPECT_EQ(total.operations[1].name, "w");
    ASSERT_EQ(stage.operations.size(), 2U);
    EXPECT_EQ(stage.operations[0].counters.ok(), 2U);

    // A one-operation mix has no per-stage operation rows (they would repeat the stage's).
    stats::RunResult single_step = step;
    single_step.operations.resize(1);
    stats::StageResult single;
    merge_step(total, single_step, &single);
    EXPECT_TRUE(single.operations.empty());
    EXPECT_EQ(single.counters.ok(), 1U);
}

TEST(RunScenario, StagedClosedLoopRunHasPerStageResults) {
    Scenario s = parse_scenario(R"(
connections: 1
depth: 2
slave_threads: 1
threads: 1
stage_step: 250ms
stages:
  - {name: ramp, duration: 500ms, connections: 4}
  - {name: hold, duration: 300ms, ramp: constant}
operations:
  - {name: r, function: 3, address: 0-99, quantity: 5}
thresholds:
  - error_rate == 0
  - transactions > 0
  - {operation: r, check: "max < 10s"}
)",
                                "staged.yaml");
    const load::LoadResult r = run_scenario(s);
    ASSERT_TRUE(r.ok) << r.error;
    ASSERT_EQ(r.run.stages.size(), 2U);
    EXPECT_EQ(r.run.stages[0].name, "ramp");
    EXPECT_EQ(r.run.stages[1].index, 2U);
    EXPECT_GT(r.run.stages[0].counters.ok(), 0U);
    EXPECT_GT(r.run.stages[1].counters.ok(), 0U);
    EXPECT_EQ(r.run.stages[0].counters.ok() + r.run.stages[1].counters.ok(), r.run.counters.ok());
    EXPECT_EQ(r.run.stages[0].start_offset_ns, 0U);
    EXPECT_EQ(r.run.stages[0].end_offset_ns, r.run.stages[1].start_offset_ns);
    EXPECT_EQ(r.run.stages[1].end_offset_ns, r.run.metadata.measured_duration_ns);
    EXPECT_EQ(r.run.metadata.connections, 4U);
    ASSERT_EQ(r.run.thresholds.size(), 3U);
    EXPECT_TRUE(r.run.thresholds_passed());
}

TEST(MergeStep, ShortLastIntervalsAreTrimmedOrFolded) {
    stats::RunResult step;
    step.metadata.measured_duration_ns = 1'200'000'000;  // 1.2 s: a 0.2 s sliver at the end
    stats::IntervalSummary full;
    full.duration_ns = 1'000'000'000;
    full.transactions = 100;
    stats::IntervalSummary sliver = full;
    sliver.index = 1;
    sliver.start_offset_ns = 1'000'000'000;
    sliver.transactions = 20;
    step.timeline = {full, sliver};
    stats::RunResult total;
    merge_step(total, step, nullptr);
    ASSERT_EQ(total.timeline.size(), 1U);
    EXPECT_EQ(total.timeline[0].transactions, 120U);
    EXPECT_EQ(total.timeline[0].duration_ns, 1'200'000'000U);

    stats::RunResult short_step;  // a 0.3 s step: its only interval covers 0.3 s
    short_step.metadata.measured_duration_ns = 300'000'000;
    short_step.timeline = {full};
    merge_step(total, short_step, nullptr);
    ASSERT_EQ(total.timeline.size(), 2U);
    EXPECT_EQ(total.timeline[1].duration_ns, 300'000'000U);
    EXPECT_EQ(total.timeline[1].start_offset_ns, 1'200'000'000U);
}

TEST(RunScenario, ExpectCountsMismatchesAgainstTheEmbeddedSlave) {
    Scenario s = parse_scenario(R"(
connections: 2
depth: 2
slave_threads: 1
threads: 1
duration: 400ms
slave:
  init: [{table: holding_registers, address: 100, value: 7, count: 10}]
operations:
  - {name: good, function: 3, address: 100-109, quantity: 10, expect: {value: 7}}
  - {name: bad, function: 3, address: 100-109, quantity: 10, expect: {value: 8}}
thresholds:
  - {operation: good, check: mismatches == 0}
  - {operation: bad, check: mismatches == 0}
)",
                                "expect.yaml");
    const load::LoadResult r = run_scenario(s);
    ASSERT_TRUE(r.ok) << r.error;
    ASSERT_EQ(r.run.operations.size(), 2U);
    EXPECT_GT(r.run.operations[0].counters.ok(), 0U);
    EXPECT_EQ(r.run.operations[0].counters.count(stats::Outcome::ValueMismatch), 0U);
    EXPECT_GT(r.run.operations[1].counters.count(stats::Outcome::ValueMismatch), 0U);
    EXPECT_EQ(r.run.operations[1].counters.ok(), 0U);
    ASSERT_EQ(r.run.thresholds.size(), 2U);
    EXPECT_TRUE(r.run.thresholds[0].passed);
    EXPECT_FALSE(r.run.thresholds[1].passed);
}

TEST(RunScenario, StopFlagEndsAStagedRunEarly) {
    Scenario s = parse_scenario(
        "stages: [{duration: 30s}]\nslave_threads: 1\nthreads: 1\nconnections: 1\n"
        "operations: [{function: 3}]\n",
        "stop.yaml");
    std::atomic<bool> stop{true};
    RunHooks hooks;
    hooks.stop = &stop;
    const load::LoadResult r = run_scenario(s, hooks);
    EXPECT_EQ(r.run.counters.transactions_sent, 0U);
}

TEST(RunScenario, UnreachableTargetIsAnError) {
    // Port 1 on loopback: nothing listens there.
    Scenario s = parse_scenario(
        "target: 127.0.0.1:1\nconnect_timeout: 500ms\nduration: 1s\nconnections: 1\n"
        "operations: [{function: 3}]\n",
        "down.yaml");
    const load::LoadResult r = run_scenario(s);
    EXPECT_EQ(r.run.counters.ok(), 0U);
    EXPECT_FALSE(r.ok && r.run.counters.ok() > 0);
}

}  // namespace
}  // namespace mbstorm::scenario
