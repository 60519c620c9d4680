// Valid scenarios: every key lands in the plan, defaults are filled, overrides apply, and the
// printed scenario reads back to the same scenario.
#include <gtest/gtest.h>

#include <filesystem>

#include "must_parse.hpp"
#include "scenario/print.hpp"
#include "scenario/scenario.hpp"
#include "slave/device_yaml_print.hpp"

namespace mbstorm::scenario {
namespace {

using namespace std::chrono_literals;

constexpr const char* kFull = R"(
name: full
description: every key
slave_threads: 1
slave:
  init:
    - {table: holding_registers, address: 100, value: 7, count: 10}
threads: 2
connections: 4
depth: 3
model: open
rate: 1500.5
arrival: poisson
warmup: 250ms
timeout: 20ms
connect_timeout: 2s
connect_rate: 500
source_addr: 127.0.0.2-127.0.0.3,::1
reconnect_backoff: {min: 10ms, max: 2s}
late_threshold: 2ms
allow_writes: true
seed: 42
stages:
  - {name: up, duration: 2s, rate: 3000}
  - {duration: 1s, connections: 8, ramp: constant}
operations:
  - name: r
    function: read_holding_registers
    unit: 7
    address: 40101-40110
    quantity: 10
    distribution: zipf
    zipf_exponent: 1.5
    weight: 3
    expect: {value: 7}
    thresholds: [p99 < 5ms]
  - function: 0x10
    address: 0x100-0x1FF
    quantity: 4
    values: {mode: counter, start: 10, step: 3}
  - function: write_single_coil
    address: 00001-00010
    values: {mode: pattern, pattern: [1, 0]}
  - function: 0x17
    address: 0-20
    quantity: 5
    write_quantity: 3
    values: random
  - function: mask_write_register
    address: 9
    and_mask: 0xF0F0
    values: 0x0101
  - function: encapsulated_interface
    device_id_code: 2
  - function: 3
thresholds:
  - error_rate < 0.1%
  - throughput > 50k/s
  - exceptions[02] == 0
  - {operation: r, check: "p99.9 <= 20ms"}
)";

TEST(ScenarioParse, EveryKeyLandsInThePlan) {
    const Scenario s = must_parse(kFull, "full.yaml");
    const load::Plan& p = s.plan;
    EXPECT_EQ(s.name, "full");
    EXPECT_EQ(s.description, "every key");
    EXPECT_TRUE(s.target.empty());
    EXPECT_EQ(s.slave_threads, 1U);
    ASSERT_EQ(s.slave.init.size(), 1U);
    EXPECT_EQ(s.slave.init[0].address, 100);
    EXPECT_EQ(p.threads, 2U);
    EXPECT_EQ(p.connections, 4U);
    EXPECT_EQ(p.depth, 3U);
    EXPECT_EQ(p.model, load::LoadModel::OpenLoop);
    EXPECT_DOUBLE_EQ(p.rate, 1500.5);
    EXPECT_EQ(p.arrival, load::Arrival::Poisson);
    EXPECT_EQ(p.warmup, 250ms);
    EXPECT_EQ(p.transaction_timeout, 20ms);
    EXPECT_EQ(p.connect_timeout, 2s);
    EXPECT_DOUBLE_EQ(p.connect_rate, 500);
    EXPECT_EQ(p.source_addresses, "127.0.0.2-127.0.0.3,::1");
    EXPECT_EQ(p.reconnect_backoff_min, 10ms);
    EXPECT_EQ(p.reconnect_backoff_max, 2s);
    EXPECT_EQ(p.late_threshold, 2ms);
    EXPECT_TRUE(p.allow_writes);
    EXPECT_EQ(p.seed, 42U);
    ASSERT_EQ(s.stages.size(), 2U);
    EXPECT_EQ(s.stages[0].name, "up");
    EXPECT_EQ(s.stages[0].ramp, load::Ramp::Linear);
    EXPECT_EQ(s.stages[1].name, "stage 2");
    EXPECT_EQ(s.stages[1].ramp, load::Ramp::Constant);
    EXPECT_EQ(*s.stages[1].connections, 8U);
    EXPECT_EQ(p.duration, 3s);  // the sum of the stages
    EXPECT_EQ(s.total_duration(), 3s);

    ASSERT_EQ(p.operations.size(), 7U);
    const auto& r = p.operations[0];
    EXPECT_EQ(r.name, "r");
    EXPECT_EQ(r.function, 0x03);
    EXPECT_EQ(r.unit_id, 7);
    EXPECT_EQ(r.first_address, 100);  // 40101 = holding register 100
    EXPECT_EQ(*r.last_address, 109);
    EXPECT_EQ(r.address_mode, load::AddressMode::Zipf);
    EXPECT_DOUBLE_EQ(r.zipf_exponent, 1.5);
    EXPECT_EQ(r.weight, 3U);
    ASSERT_TRUE(s.expectations[0].active);
    EXPECT_EQ(*s.expectations[0].value, 7);

    EXPECT_EQ(p.operations[1].name, "write_multiple_registers");
    EXPECT_EQ(p.operations[1].first_address, 0x100);
    EXPECT_EQ(*p.operations[1].last_address, 0x1FF);
    EXPECT_EQ(p.operations[1].values.mode, load::ValueMode::Counter);
    EXPECT_EQ(p.operations[1].values.value, 10);
    EXPECT_EQ(p.operations[1].values.step, 3);
    EXPECT_FALSE(s.expectations[1].active);

    EXPECT_EQ(p.operations[2].function, 0x05);
    EXPECT_EQ(p.operations[2].first_address, 0);  // coil reference 00001
    EXPECT_EQ(p.operations[2].quantity, 1);       // FC05 default
    EXPECT_EQ(p.operations[2].values.pattern, (std::vector<std::uint16_t>{1, 0}));

    EXPECT_EQ(p.operations[3].write_quantity, 3);
    EXPECT_EQ(p.operations[3].values.mode, load::ValueMode::Random);
    EXPECT_EQ(p.operations[4].and_mask, 0xF0F0);
    EXPECT_EQ(p.operations[4].values.value, 0x0101);
    EXPECT_EQ(p.operations[5].device_id_code, 2);
    EXPECT_EQ(p.operations[6].quantity, 10);  // FC03 default
    EXPECT_EQ(p.operations[6].name, "read_holding_registers");

    ASSERT_EQ(s.thresholds.size(), 5U);
    EXPECT_EQ(s.thresholds[0].operation, "r");
    EXPECT_EQ(s.thresholds[0].text, "p99 < 5ms");
    EXPECT_EQ(s.thresholds[1].text, "error_rate < 0.1%");
    EXPECT_DOUBLE_EQ(s.thresholds[2].limit, 50000);
    EXPECT_EQ(s.thresholds[3].exception_code, 2);
    EXPECT_EQ(s.thresholds[4].operation, "r");
    EXPECT_DOUBLE_EQ(s.thresholds[4].percentile, 99.9);
}

TEST(ScenarioParse, DefaultsForAMinimalFile) {
    const Scenario s = must_parse("operations:\n  - function: 4\n", "dir/min.yaml");
    EXPECT_EQ(s.name, "min");
    EXPECT_TRUE(s.target.empty());
    EXPECT_EQ(s.plan.connections, kDefaultConnections);
    EXPECT_EQ(s.plan.depth, kDefaultDepth);
    EXPECT_EQ(s.plan.model, load::LoadModel::ClosedLoop);
    EXPECT_EQ(s.plan.duration, 10s);
    EXPECT_EQ(s.plan.transaction_timeout, 1s);
    EXPECT_EQ(s.plan.operations[0].first_address, 0);
    EXPECT_FALSE(s.plan.operations[0].last_address.has_value());
    EXPECT_TRUE(s.thresholds.empty());
    EXPECT_TRUE(s.stages.empty());
}

TEST(ScenarioParse, RateAloneMeansOpenLoopAndDefaultNamesStayUnique) {
    const Scenario s = must_parse(
        "rate: 100\ntarget: '[::1]:1502'\noperations:\n  - {function: 3}\n  - {function: 3}\n",
        "x.yaml");
    EXPECT_EQ(s.plan.model, load::LoadModel::OpenLoop);
    EXPECT_EQ(s.target, "[::1]:1502");
    EXPECT_EQ(s.plan.operations[0].name, "read_holding_registers");
    EXPECT_EQ(s.plan.operations[1].name, "read_holding_registers_2");
}

TEST(ScenarioParse, ZeroDurationIsFineWithATransactionCount) {
    const Scenario s =
        must_parse("duration: 0\ntransactions: 500\noperations: [{function: 3}]\n", "t.yaml");
    EXPECT_EQ(s.plan.transactions, 500U);
    EXPECT_EQ(s.plan.duration, 0s);
}

// The same, member by member rather than as text: a printer that left a member out (or wrote
// a default in its place) prints its own output identically, yet the plan read back differs.
// The scenario_yaml fuzz harness checks the same on every scenario it finds.
void expect_reads_back_member_by_member(const Scenario& s) {
    const Scenario again = must_parse(format_scenario(s), s.source);
    EXPECT_EQ(again.name, s.name);
    EXPECT_EQ(again.description, s.description);
    EXPECT_EQ(again.target, s.target);
    EXPECT_TRUE(again.plan.operations == s.plan.operations);
    EXPECT_TRUE(again.plan == s.plan);
    EXPECT_TRUE(again.stages == s.stages);
    EXPECT_TRUE(again.thresholds == s.thresholds);
    EXPECT_TRUE(again.expectations == s.expectations);
    EXPECT_TRUE(again.slave == s.slave);
    EXPECT_EQ(again.slave_threads, s.slave_threads);
}

TEST(ScenarioPrint, ReadsBackToTheSamePlanMemberByMember) {
    {
        SCOPED_TRACE("full.yaml");
        expect_reads_back_member_by_member(must_parse(kFull, "full.yaml"));
    }
    const std::filesystem::path folder = std::filesystem::path(MBSTORM_SOURCE_DIR) / "scenarios";
    std::size_t files = 0;
    for (const auto& entry : std::filesystem::directory_iterator(folder)) {
        if (entry.path().extension() != ".yaml") continue;
        SCOPED_TRACE(entry.path().string());
        expect_reads_back_member_by_member(must_load(entry.path().string()));
        ++files;
    }
    EXPECT_GE(files, 7u);
}

// Found by the scenario_yaml harness once it compared members: a top-level threshold that
// names an operation was printed under that operation, so the printed scenario read back with
// its thresholds in another order, and with a longer list under the operation than the cap
// allows (the file was accepted, its printed form refused).
TEST(ScenarioPrint, ThresholdsReadBackWhereTheyWereWritten) {
    const Scenario s = must_parse(R"(
operations:
  - {name: r, function: 3, thresholds: ["p99 < 5ms"]}
thresholds:
  - error_rate < 0.1%
  - {operation: r, check: "p99.9 <= 20ms"}
)",
                                  "t.yaml");
    ASSERT_EQ(s.thresholds.size(), 3u);
    EXPECT_TRUE(s.thresholds[0].in_operation);
    EXPECT_FALSE(s.thresholds[2].in_operation);
    EXPECT_EQ(s.thresholds[2].operation, "r");
    const std::string printed = format_scenario(s);
    EXPECT_NE(printed.find(R"({operation: r, check: "p99.9 <= 20ms"})"), std::string::npos)
        << printed;
    const Scenario again = must_parse(printed, "t.yaml");
    EXPECT_TRUE(again.thresholds == s.thresholds);
}

TEST(ScenarioPrint, ThresholdsWithinTheCapsPrintWithinTheCaps) {
    // 600 under the operation and 500 more for it in the top-level list: each list within
    // kMaxThresholds, the operation's 1100 in all are not one list when printed.
    std::string text = "operations:\n  - name: r\n    function: 3\n    thresholds:\n";
    for (int i = 1; i <= 600; ++i) text += "      - p99 < " + std::to_string(i) + "ms\n";
    text += "thresholds:\n";
    for (int i = 1; i <= 500; ++i)
        text += "  - {operation: r, check: \"p50 < " + std::to_string(i) + "ms\"}\n";
    const Scenario s = must_parse(text, "cap.yaml");
    ASSERT_EQ(s.thresholds.size(), 1100u);
    Scenario again;
    ASSERT_NO_THROW(again = must_parse(format_scenario(s), "cap.yaml"));
    EXPECT_TRUE(again.thresholds == s.thresholds);
}

TEST(ScenarioPrint, ReadsBackToTheSameScenario) {
    const Scenario s = must_parse(kFull, "full.yaml");
    const std::string printed = format_scenario(s);
    const Scenario again = must_parse(printed, "printed.yaml");
    // The first line names the source file; everything after it must be identical.
    const auto body = [](const std::string& text) { return text.substr(text.find('\n')); };
    EXPECT_EQ(body(format_scenario(again)), body(printed));
    // Defaults are written out.
    EXPECT_NE(printed.find("connect_timeout: 2s"), std::string::npos) << printed;
    EXPECT_NE(printed.find("source_addr: 127.0.0.2-127.0.0.3,::1"), std::string::npos) << printed;
    EXPECT_NE(printed.find("address: 100-109"), std::string::npos) << printed;
    EXPECT_NE(printed.find("function: read_holding_registers"), std::string::npos);
    EXPECT_NE(printed.find("init"), std::string::npos) << printed;
}

TEST(ScenarioPrint, MinimalFileShowsEveryDefault) {
    const std::string printed =
        format_scenario(must_parse("operations: [{function: 6}]\n", "m.yaml"));
    for (const char* key :
         {"threads: 0", "connections: 16", "depth: 16", "model: closed", "duration: 10s",
          "transactions: 0", "warmup: 0s", "timeout: 1s", "connect_timeout: 3s",
          "connect_rate: 10000", "allow_writes: false", "seed: 1", "quantity: 1", "unit: 1",
          "distribution: sequential", "mode: constant", "weight: 1"}) {
        EXPECT_NE(printed.find(key), std::string::npos) << key << " missing in\n" << printed;
    }
}

// The embedded slave is printed resolved (every device key, defaults included), not as written.
TEST(ScenarioPrint, SlaveIsPrintedResolvedAndReadsBack) {
    const Scenario s = must_parse(R"(
operations: [{function: 3}]
slave:
  units: [1, "3-5"]
  init:
    - {table: holding_registers, address: 10, type: float32, values: [1.5], units: [4]}
    - {table: input_registers, address: 0, count: 3, random: {min: 1, max: 9, seed: 5}}
  counters:
    - {address: 7, step: -2}
    - {address: 8, mode: interval, interval_ms: 250, units: [1]}
  simulate:
    - {table: coils, address: 3, wave: square, period_ms: 100, amplitude: 1, duty: 0.1}
  faults:
    delay: {fixed_ms: 0.5}
    exception: {rate: 0.5, code: 6}
)",
                                  "slave.yaml");
    const std::string printed = format_scenario(s);
    for (const char* key :
         {"units: [1, 3-5]", "unknown_unit: gateway_target_failed", "diagnostics: true",
          "files: {count: 4, records: 10000}", "delay: {fixed_ms: 0.5}",
          "stall: {duration_ms: 0, every_ms: 0}", "exception: {rate: 0.5, code: 6}", "drop_rate: 0",
          "mode: interval", "wave: square", "vendor_name: \"mbstorm\""}) {
        EXPECT_NE(printed.find(key), std::string::npos) << key << " missing in\n" << printed;
    }
    const Scenario again = must_parse(printed, "printed.yaml");
    EXPECT_EQ(slave::format_device_yaml(again.slave), slave::format_device_yaml(s.slave));
    ASSERT_EQ(again.slave.init.size(), 2U);
    EXPECT_EQ(again.slave.init[0].words, s.slave.init[0].words);  // float32 as its two words
    EXPECT_EQ(again.slave.init[1].words, s.slave.init[1].words);  // the drawn random values
    EXPECT_EQ(again.slave.read_counters[0].step, s.slave.read_counters[0].step);
    EXPECT_EQ(again.slave.faults.delay.fixed_ns, 500'000U);
}

TEST(ScenarioPrint, NoSlaveKeyPrintsTheDefaultSlaveButATargetPrintsNone) {
    const std::string printed =
        format_scenario(must_parse("operations: [{function: 3}]\n", "plain.yaml"));
    const Scenario again = must_parse(printed, "printed.yaml");
    EXPECT_EQ(slave::format_device_yaml(again.slave),
              slave::format_device_yaml(slave::DeviceDescription{}));
    for (const char* key : {"slave:", "units: shared", "holding_registers: 65536", "init: []",
                            "delay: none", "no_answer_rate: 0"}) {
        EXPECT_NE(printed.find(key), std::string::npos) << key << " missing in\n" << printed;
    }

    const std::string with_target = format_scenario(
        must_parse("target: 127.0.0.1:502\noperations: [{function: 3}]\n", "t.yaml"));
    EXPECT_EQ(with_target.find("slave"), std::string::npos) << with_target;
}

TEST(ScenarioOverrides, FlagsReplaceFileValues) {
    Scenario s = must_parse(kFull, "full.yaml");
    Overrides o;
    o.target = "127.0.0.1:1502";
    o.connections = 2;
    o.depth = 1;
    o.duration = 300ms;  // stages are scaled to fit
    o.threads = 1;
    ASSERT_TRUE(apply_overrides(s, o).ok());
    EXPECT_EQ(s.target, "127.0.0.1:1502");
    EXPECT_EQ(s.plan.connections, 2U);
    EXPECT_FALSE(s.stages[1].connections.has_value());
    EXPECT_EQ(s.plan.depth, 1U);
    EXPECT_EQ(s.stages[0].duration, 200ms);
    EXPECT_EQ(s.stages[1].duration, 100ms);
    EXPECT_EQ(s.total_duration(), 300ms);
    EXPECT_EQ(s.plan.warmup, 250ms);
}

TEST(ScenarioOverrides, RateSwitchesToOpenLoopAndBadValuesAreReported) {
    Scenario s = must_parse("operations: [{function: 3}]\n", "o.yaml");
    Overrides o;
    o.rate = 500;
    ASSERT_TRUE(apply_overrides(s, o).ok());
    EXPECT_EQ(s.plan.model, load::LoadModel::OpenLoop);

    Overrides bad_target;
    bad_target.target = "nowhere:";
    Error problems = apply_overrides(s, bad_target);
    EXPECT_EQ(problems.code(), ErrorCode::InvalidInput);
    EXPECT_EQ(problems.message().find('\n'), std::string::npos) << "one problem";
    EXPECT_NE(problems.message().find("port 502 if omitted"), std::string::npos);

    Overrides zero;
    zero.duration = 0s;
    problems = apply_overrides(s, zero);
    ASSERT_FALSE(problems.ok());
    EXPECT_NE(problems.message().find("duration"), std::string::npos) << problems.text();

    Scenario staged =
        must_parse("stages: [{duration: 5s}]\noperations: [{function: 3}]\n", "s.yaml");
    problems = apply_overrides(staged, zero);
    ASSERT_FALSE(problems.ok());
    EXPECT_NE(problems.message().find("cannot scale the stages"), std::string::npos);
}

TEST(ScenarioFromPlan, PrintsAFlagOnlyRun) {
    load::Plan plan;
    plan.operations.push_back({});
    plan.operations[0].name = "read_holding_registers";
    plan.connections = 3;
    const std::string printed = format_scenario(scenario_from_plan(plan, "127.0.0.1:502"));
    EXPECT_NE(printed.find("target: 127.0.0.1:502"), std::string::npos) << printed;
    EXPECT_NE(printed.find("connections: 3"), std::string::npos);
    EXPECT_NO_THROW((void)must_parse(printed, "flags.yaml")) << printed;
}

}  // namespace
}  // namespace mbstorm::scenario
