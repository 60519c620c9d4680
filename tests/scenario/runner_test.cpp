// Staged schedules, result merging, and end-to-end runs against the embedded reference slave.
// Every run here is bounded (well under 2 s of traffic) and loopback only.
#include <gtest/gtest.h>

#include "must_parse.hpp"
#include "scenario/runner.hpp"
#include "scenario/scenario.hpp"

namespace mbstorm::scenario {
namespace {

using namespace std::chrono_literals;

TEST(EnginePlan, CarriesTheStagesToTheEngine) {
    Scenario s = must_parse(R"(
rate: 100
stages:
  - {name: up, duration: 2s, rate: 1100}
  - {duration: 1500ms, connections: 3, ramp: constant}
operations: [{function: 3}]
)",
                            "s.yaml");
    const load::Plan plan = engine_plan(s);
    ASSERT_EQ(plan.stages.size(), 2U);
    EXPECT_EQ(plan.stages[0].name, "up");
    EXPECT_EQ(plan.stages[0].target_rate, 1100);
    EXPECT_FALSE(plan.stages[0].target_connections);
    EXPECT_EQ(plan.stages[0].ramp, load::Ramp::Linear);
    EXPECT_EQ(plan.stages[1].name, "stage 2");
    EXPECT_EQ(plan.stages[1].target_connections, 3U);
    EXPECT_EQ(plan.stages[1].ramp, load::Ramp::Constant);
    EXPECT_TRUE(load::validate_plan(plan).ok() ||
                load::validate_plan(plan).message().find("port") != std::string::npos);
}

TEST(RunScenario, StagedClosedLoopRunHasPerStageResults) {
    Scenario s = must_parse(R"(
connections: 1
depth: 2
slave_threads: 1
threads: 1
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
    ASSERT_TRUE(r.ok()) << r.error;
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
    // Connections stay open across the ramp and the stage boundary: four opens, no re-opens.
    EXPECT_EQ(r.run.connections.opened, 4U);
    EXPECT_EQ(r.run.connections.reconnects, 0U);
    ASSERT_EQ(r.run.thresholds.size(), 3U);
    EXPECT_TRUE(r.run.thresholds_passed());
}

TEST(RunScenario, ConnectionsCloseAtZeroAndOpenAgainWithoutErrors) {
    Scenario s = must_parse(R"(
connections: 3
depth: 4
slave_threads: 1
threads: 1
stages:
  - {name: three, duration: 300ms, ramp: constant}
  - {name: none, duration: 300ms, connections: 0, ramp: constant}
  - {name: two, duration: 300ms, connections: 2, ramp: constant}
operations: [{function: 3, address: 0-99, quantity: 5}]
)",
                            "zero.yaml");
    const load::LoadResult r = run_scenario(s);
    ASSERT_TRUE(r.ok()) << r.error;
    ASSERT_EQ(r.run.stages.size(), 3U);
    EXPECT_GT(r.run.stages[0].counters.ok(), 0U);
    // Nothing is sent in a stage without connections; the surplus drained, never errored.
    EXPECT_EQ(r.run.stages[1].counters.transactions_sent, 0U);
    EXPECT_GT(r.run.stages[2].counters.ok(), 0U);
    EXPECT_EQ(r.run.counters.errors(), 0U);
    EXPECT_EQ(r.run.connections.opened, 5U);  // 3, then 2 again after the pause
    EXPECT_EQ(r.run.connections.reconnects, 0U);
    EXPECT_EQ(r.run.counters.transactions_sent, r.run.counters.completed() + r.pending_at_end);
}

TEST(RunScenario, OpenLoopRampFollowsTheScheduledRate) {
    Scenario s = must_parse(R"(
rate: 200
connections: 4
depth: 8
slave_threads: 1
threads: 1
stages:
  - {name: ramp, duration: 1s, rate: 1800}
  - {name: hold, duration: 1s}
operations: [{function: 3, quantity: 2}]
)",
                            "ramp.yaml");
    const load::LoadResult r = run_scenario(s);
    ASSERT_TRUE(r.ok()) << r.error;
    ASSERT_EQ(r.run.stages.size(), 2U);
    // A linear ramp 200 -> 1800 over 1 s sends its mean, 1000; the hold sends 1800.
    EXPECT_NEAR(static_cast<double>(r.run.stages[0].counters.transactions_sent), 1000, 100);
    EXPECT_NEAR(static_cast<double>(r.run.stages[1].counters.transactions_sent), 1800, 150);
    EXPECT_EQ(r.run.connections.opened, 4U);
    ASSERT_GE(r.run.timeline.size(), 2U);
    EXPECT_NEAR(r.run.timeline[0].target_rate, 1000, 1);
    EXPECT_NEAR(r.run.timeline[1].target_rate, 1800, 1);
    EXPECT_EQ(r.run.timeline[0].open_connections, 4U);
    EXPECT_DOUBLE_EQ(r.run.metadata.rate_per_second, 1800);
    // The schedule as it was, stage by stage.
    EXPECT_DOUBLE_EQ(r.run.stages[0].rate_from, 200);
    EXPECT_DOUBLE_EQ(r.run.stages[0].rate_to, 1800);
    EXPECT_DOUBLE_EQ(r.run.stages[1].rate_from, 1800);
    EXPECT_DOUBLE_EQ(r.run.stages[1].rate_to, 1800);
    EXPECT_EQ(r.run.stages[1].connections_to, 4U);
}

// Connections opened at 4/s cannot reach 6 in 400 ms: every threshold may pass on the load
// that was there, but the load the scenario describes never was, and the run fails.
TEST(RunScenario, ThresholdsFailWhenThePlanWasNotCarriedOut) {
    Scenario s = must_parse(R"(
connections: 6
connect_rate: 4
depth: 1
slave_threads: 1
threads: 1
duration: 400ms
operations: [{function: 3}]
thresholds:
  - error_rate == 0
)",
                            "short.yaml");
    const load::LoadResult r = run_scenario(s);
    ASSERT_TRUE(r.ok()) << r.error;
    ASSERT_FALSE(r.run.shortfalls.empty());
    ASSERT_EQ(r.run.thresholds.size(), 2U);
    EXPECT_TRUE(r.run.thresholds[0].passed);
    EXPECT_EQ(r.run.thresholds[1].expression, "plan carried out");
    EXPECT_FALSE(r.run.thresholds[1].passed);
    EXPECT_NE(r.run.thresholds[1].observed_text.find("of 6 opened"), std::string::npos)
        << r.run.thresholds[1].observed_text;
    EXPECT_FALSE(r.run.thresholds_passed());
}

TEST(RunScenario, ExpectCountsMismatchesAgainstTheEmbeddedSlave) {
    Scenario s = must_parse(R"(
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
    ASSERT_TRUE(r.ok()) << r.error;
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
    Scenario s = must_parse(
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
    Scenario s = must_parse(
        "target: 127.0.0.1:1\nconnect_timeout: 500ms\nduration: 1s\nconnections: 1\n"
        "operations: [{function: 3}]\n",
        "down.yaml");
    const load::LoadResult r = run_scenario(s);
    EXPECT_EQ(r.run.counters.ok(), 0U);
    EXPECT_FALSE(r.ok() && r.run.counters.ok() > 0);
}

}  // namespace
}  // namespace mbstorm::scenario
