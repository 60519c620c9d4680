// Every way a scenario file can be wrong: each is rejected before any traffic, with the file,
// line and column, and (for values) the valid range.
#include <gtest/gtest.h>

#include <string>

#include "must_parse.hpp"
#include "scenario/scenario.hpp"

namespace mbstorm::scenario {
namespace {

struct BadCase {
    const char* label;
    const char* yaml;
    const char* message;  // substring of the error
    int line;             // 1-based; 0: do not check the position
    int column;
};

// A minimal valid operation list to append where the case is about something else.
#define OPS "operations:\n  - {function: 3, address: 0-99}\n"

const BadCase kCases[] = {
    // --- the document
    {"syntax", "connections: [1, 2\n" OPS, "YAML syntax", 0, 0},
    {"empty", "", "the scenario is empty", 0, 0},
    {"not a mapping", "- 1\n- 2\n", "must be a mapping of keys", 1, 1},
    {"unknown top key", "conections: 4\n" OPS,
     "unknown key 'conections' in the scenario; did you mean 'connections'?", 1, 1},
    {"duplicate key", "depth: 2\ndepth: 3\n" OPS, "duplicate key 'depth'", 2, 1},
    {"binary out of range", "depth: 0b1000000000000001\n" OPS,
     "depth: 0b1000000000000001 is out of range (valid 1..32768)", 1, 8},
    {"non-scalar key", "? [a, b]\n: 1\n" OPS, "keys must be plain words", 1, 3},
    // --- top-level values
    {"connections zero", "connections: 0\n" OPS, "connections: 0 is out of range (valid 1..100000)",
     1, 14},
    {"connections too many", "connections: 100001\n" OPS, "valid 1..100000", 1, 14},
    {"connections not integer", "connections: many\n" OPS,
     "'many' is not a whole number (valid 1..100000)", 1, 14},
    {"connections a list", "connections: [1]\n" OPS, "must be a single value", 1, 14},
    {"depth range", "depth: 40000\n" OPS, "depth: 40000 is out of range (valid 1..32768)", 1, 8},
    {"threads range", "threads: 2000\n" OPS, "valid 0..1024", 1, 10},
    {"slave_threads range", "slave_threads: -1\n" OPS, "valid 0..1024", 1, 16},
    {"model choice", "model: half-open\n" OPS, "'half-open' is not one of closed, open", 1, 8},
    {"rate not a number", "rate: fast\n" OPS, "'fast' is not a number", 1, 7},
    {"rate negative", "rate: -5\n" OPS, "out of range (valid 0..1e+09)", 1, 7},
    {"arrival choice", "rate: 10\narrival: bursty\n" OPS, "not one of even, poisson", 2, 10},
    {"duration zero", "duration: 0s\n" OPS, "duration: 0s never ends the run (valid > 0s", 1, 11},
    {"duration garbage", "duration: soon\n" OPS, "'soon' is not a duration (e.g. 500ms", 1, 11},
    {"duration bad unit", "duration: 10 parsecs\n" OPS, "is not a duration", 1, 11},
    {"warmup negative", "duration: 5s\nwarmup: -1s\n" OPS, "warmup", 2, 9},
    {"timeout too short", "timeout: 100us\n" OPS, "timeout: 100us is out of range (valid 1ms..1h)",
     1, 10},
    {"connect_timeout zero", "connect_timeout: 0\n" OPS, "out of range (valid > 0s..1h)", 1, 18},
    {"connect_rate zero", "connect_rate: 0\n" OPS, "valid 1..1e+07", 1, 15},
    {"source_addr bad range", "source_addr: 127.0.0.1-x\n" OPS,
     "source_addr: '127.0.0.1-x' is not a range FIRST-LAST", 1, 14},
    {"backoff unknown key", "reconnect_backoff: {minimum: 1s}\n" OPS,
     "unknown key 'minimum' in reconnect_backoff", 1, 21},
    {"backoff inverted", "reconnect_backoff: {min: 2s, max: 1s}\n" OPS, "max 1s is below min 2s", 1,
     20},
    {"allow_writes bool", "allow_writes: maybe\n" OPS, "'maybe' is not true or false", 1, 15},
    {"seed negative", "seed: -1\n" OPS, "seed: -1 is out of range", 1, 7},
    {"stage_step gone", "stage_step: 1s\nstages: [{duration: 1s}]\n" OPS,
     "unknown key 'stage_step'", 1, 1},
    {"rate in closed loop", "model: closed\nrate: 100\n" OPS, "rate: not used in a closed-loop run",
     2, 7},
    {"open loop without rate", "model: open\n" OPS, "an open-loop run needs a rate > 0", 1, 8},
    {"arrival in closed loop", "arrival: poisson\n" OPS, "arrival: only used in an open-loop run",
     1, 10},
    {"arrival with model closed", "model: closed\narrival: even\n" OPS,
     "arrival: only used in an open-loop run", 2, 10},
    // --- target and slave
    {"target empty port", "target: '127.0.0.1:'\n" OPS, "port 502 if omitted", 1, 9},
    {"target port range", "target: 127.0.0.1:70000\n" OPS, "the port must be 1..65535", 1, 9},
    {"target empty host", "target: ':502'\n" OPS, "the host is empty", 1, 9},
    {"slave with target", "target: 127.0.0.1:502\nslave: {}\n" OPS,
     "slave: only used with the embedded slave", 2, 8},
    {"slave bad key", "slave:\n  tabels: {}\n" OPS, "unknown key 'tabels'", 2, 3},
    // --- operations
    {"operations missing", "connections: 2\n", "`operations` is required", 1, 1},
    {"operations empty", "operations: []\n", "a list of at least one operation", 1, 13},
    {"operations a map", "operations: {function: 3}\n", "a list of at least one operation", 1, 13},
    {"operation not a map", "operations:\n  - 3\n", "operations[0] must be a mapping", 2, 5},
    {"function missing", "operations:\n  - {address: 0}\n", "`function` is required", 2, 5},
    {"function unknown name", "operations:\n  - {function: read_holding_regs}\n",
     "function 'read_holding_regs' is not a function code; write a name "
     "(write_multiple_registers), hex with 0x (0x10) or decimal (16) (generated: 0x01 read_coils",
     2, 16},
    {"function not generatable", "operations:\n  - {function: 0x14}\n",
     "function 0x14 read_file_record cannot be generated", 2, 16},
    {"function out of range", "operations:\n  - {function: 300}\n",
     "function '300' is out of range 1..127 (0x01..0x7F)", 2, 16},
    {"unknown op key", "operations:\n  - {function: 3, adress: 5}\n",
     "unknown key 'adress' in operations[0]", 2, 19},
    {"quantity over limit", "operations:\n  - {function: read_holding_registers, quantity: 126}\n",
     "quantity for 0x03 read_holding_registers: 126 is out of range (valid 1..125)", 2, 50},
    {"quantity over coil limit", "operations:\n  - {function: 15, quantity: 1969}\n",
     "valid 1..1968", 2, 30},
    {"quantity zero", "operations:\n  - {function: 1, quantity: 0}\n", "valid 1..2000", 2, 29},
    {"quantity on FC07", "operations:\n  - {function: 7, quantity: 2}\n",
     "quantity does not apply to 0x07 read_exception_status", 2, 19},
    {"address on FC11", "operations:\n  - {function: 0x11, address: 2}\n",
     "address does not apply to 0x11 report_server_id", 2, 22},
    {"address garbage", "operations:\n  - {function: 3, address: here}\n",
     "address 'here' is not an address: give a 0-based protocol address 0..65535 (decimal, or 0x "
     "hex), a range FIRST-LAST, or reference numbers like 40001-40100",
     2, 28},
    {"address too big", "operations:\n  - {function: 3, address: 70000}\n", "is not an address", 2,
     28},
    {"address reversed", "operations:\n  - {function: 3, address: 99-0}\n", "ends before it starts",
     2, 28},
    {"address mixed forms", "operations:\n  - {function: 3, address: 40001-99}\n",
     "mixes a reference number and a protocol address", 2, 28},
    {"reference wrong table", "operations:\n  - {function: 3, address: 30001-30010}\n",
     "'30001' is an input register reference: read it with 0x04 read_input_registers; for "
     "protocol address 30001 write 0x7531",
     2, 28},
    {"reference invalid", "operations:\n  - {function: 3, address: 40000}\n",
     "'40000' is not a valid reference number", 2, 28},
    {"range too small", "operations:\n  - {function: 3, address: 0-4, quantity: 10}\n",
     "address range 0-4 holds 5 items but each request needs 10", 2, 28},
    {"past 65535", "operations:\n  - {function: 3, address: 65530, quantity: 10}\n",
     "address 65530 + quantity 10 runs past 65535 (the first address must be <= 65526)", 2, 28},
    {"distribution choice", "operations:\n  - {function: 3, distribution: gaussian}\n",
     "'gaussian' is not one of sequential, uniform, zipf", 2, 33},
    {"zipf exponent zero", "operations:\n  - {function: 3, distribution: zipf, zipf_exponent: 0}\n",
     "zipf_exponent: 0 is out of range (valid > 0 and <= 10)", 2, 54},
    {"zipf exponent big", "operations:\n  - {function: 3, distribution: zipf, zipf_exponent: 11}\n",
     "valid 0..10", 2, 54},
    {"zipf exponent without zipf", "operations:\n  - {function: 3, zipf_exponent: 1.2}\n",
     "only used with distribution: zipf", 2, 34},
    {"weight zero", "operations:\n  - {function: 3, weight: 0}\n",
     "weight: 0 is out of range (valid 1..4294967295)", 2, 27},
    {"values on a read", "operations:\n  - {function: 3, values: 5}\n",
     "values does not apply to 0x03 read_holding_registers", 2, 19},
    {"values garbage", "operations:\n  - {function: 6, values: lots}\n",
     "values: 'lots' is not a value 0..65535, random, counter", 2, 27},
    {"values too big", "operations:\n  - {function: 6, values: 70000}\n", "is not a value 0..65535",
     2, 27},
    {"values mode", "operations:\n  - {function: 6, values: {mode: sine}}\n",
     "values.mode: 'sine' is not one of constant, counter, random, pattern", 2, 34},
    {"values unknown key", "operations:\n  - {function: 6, values: {mode: counter, stride: 2}}\n",
     "unknown key 'stride' in values", 2, 43},
    {"values empty pattern",
     "operations:\n  - {function: 16, quantity: 2, values: {mode: pattern}}\n",
     "mode pattern needs `pattern:", 2, 41},
    {"values pattern not list",
     "operations:\n  - {function: 16, quantity: 2, values: {pattern: 5}}\n",
     "values.pattern must be a list", 2, 51},
    {"values pattern entry",
     "operations:\n  - {function: 16, quantity: 2, values: {pattern: [1, -2]}}\n",
     "values.pattern entry: -2 is out of range (valid 0..65535)", 2, 55},
    {"values pattern with constant",
     "operations:\n  - {function: 16, quantity: 2, values: {mode: constant, pattern: [1]}}\n",
     "`pattern` is only used with mode: pattern", 2, 41},
    {"values step", "operations:\n  - {function: 6, values: {mode: counter, step: 65536}}\n",
     "values.step: 65536 is out of range", 2, 49},
    {"write_quantity wrong fc", "operations:\n  - {function: 16, write_quantity: 2}\n",
     "write_quantity does not apply to 0x10 write_multiple_registers", 2, 20},
    {"write_quantity range", "operations:\n  - {function: 0x17, write_quantity: 122}\n",
     "write_quantity: 122 is out of range (valid 1..121)", 2, 38},
    {"and_mask wrong fc", "operations:\n  - {function: 6, and_mask: 1}\n",
     "and_mask does not apply to 0x06 write_single_register", 2, 19},
    {"and_mask range", "operations:\n  - {function: 0x16, and_mask: 0x10000}\n",
     "and_mask: 0x10000 is out of range (valid 0..65535)", 2, 32},
    {"device_id_code wrong fc", "operations:\n  - {function: 3, device_id_code: 1}\n",
     "device_id_code does not apply", 2, 19},
    {"device_id_code range", "operations:\n  - {function: 0x2B, device_id_code: 5}\n",
     "device_id_code: 5 is out of range (valid 1..4)", 2, 38},
    {"unit range", "operations:\n  - {function: 3, unit: 256}\n",
     "unit: 256 is out of range (valid 0..255)", 2, 25},
    {"name empty", "operations:\n  - {function: 3, name: ''}\n", "name must not be empty", 2, 25},
    {"name duplicate", "operations:\n  - {function: 3, name: a}\n  - {function: 4, name: a}\n",
     "operation name 'a' is used twice", 3, 25},
    // --- expect
    {"expect on a write", "operations:\n  - {function: 6, expect: {value: 1}}\n",
     "expect: 0x06 write_single_register returns no values to check", 2, 27},
    {"expect empty", "operations:\n  - {function: 3, expect: {}}\n",
     "give at least one of value, min, max, values", 2, 27},
    {"expect unknown key", "operations:\n  - {function: 3, expect: {equals: 1}}\n",
     "unknown key 'equals' in expect", 2, 28},
    {"expect min above max", "operations:\n  - {function: 3, expect: {min: 5, max: 1}}\n",
     "min 5 is greater than max 1", 2, 27},
    {"expect bit value", "operations:\n  - {function: 1, expect: {value: 2}}\n",
     "expect.value: 2 is out of range (valid 0..1)", 2, 35},
    {"expect values short",
     "operations:\n  - {function: 3, address: 0-9, quantity: 2, expect: {values: [1, 2]}}\n",
     "expect.values has 2 entries but the operation reads addresses 0..9 (10 needed", 2, 63},
    // --- thresholds
    {"thresholds not a list", "thresholds: p99 < 5ms\n" OPS, "thresholds must be a list", 1, 13},
    {"threshold no comparison", "thresholds: [p99 5ms]\n" OPS, "has no comparison", 1, 14},
    {"threshold unknown metric", "thresholds: [p99x < 5ms]\n" OPS, "unknown metric 'p99x'", 1, 14},
    {"threshold percentile range", "thresholds: [p101 < 5ms]\n" OPS,
     "percentile 'p101' is out of range", 1, 14},
    {"threshold latency unit", "thresholds: [p99 < 5]\n" OPS,
     "'5' is not a latency: give a number with a unit", 1, 14},
    {"threshold rate range", "thresholds: [error_rate < 150%]\n" OPS,
     "error_rate limit '150%' is out of range (valid 0%..100%)", 1, 14},
    {"threshold rate garbage", "thresholds: [error_rate < low]\n" OPS, "'low' is not a rate", 1,
     14},
    {"threshold throughput", "thresholds: [throughput > quick]\n" OPS,
     "'quick' is not a throughput", 1, 14},
    {"threshold count", "thresholds: [errors < 1.5]\n" OPS, "'1.5' is not a count", 1, 14},
    {"threshold exception code", "thresholds: ['exceptions[2G] == 0']\n" OPS,
     "the exception code must be hex 01..FF", 1, 14},
    {"threshold no metric", "thresholds: ['< 5ms']\n" OPS, "has no metric", 1, 14},
    {"threshold no value", "thresholds: ['p99 <']\n" OPS, "has no value", 1, 14},
    {"threshold bad comparison", "thresholds: ['p99 =< 5ms']\n" OPS, "unknown comparison", 1, 14},
    {"threshold unknown operation", "thresholds: [{operation: nope, check: p99 < 5ms}]\n" OPS,
     "no operation is named 'nope'", 1, 26},
    {"threshold map without check", "thresholds: [{operation: read_holding_registers}]\n" OPS,
     "`check` is required", 1, 14},
    {"threshold map unknown key", "thresholds: [{expr: p99 < 1ms}]\n" OPS,
     "unknown key 'expr' in threshold", 1, 15},
    {"op thresholds not a list", "operations:\n  - {function: 3, thresholds: p99 < 1ms}\n",
     "thresholds must be a list", 2, 31},
    {"op threshold bad", "operations:\n  - {function: 3, thresholds: [p99 < fast]}\n",
     "not a latency", 2, 32},
    // --- stages
    {"stages not a list", "stages: {duration: 5s}\n" OPS,
     "stages must be a list of at least one stage", 1, 9},
    {"stage not a map", "stages: [5s]\n" OPS, "stages[0] must be a mapping", 1, 10},
    {"stage without duration", "stages: [{rate: 100}]\n" OPS, "stages[0]: `duration` is required",
     1, 10},
    {"stage zero duration", "stages: [{duration: 0s, rate: 10}]\n" OPS,
     "stage duration: 0s is out of range (valid > 0s..", 1, 21},
    {"stage unknown key", "stages: [{duration: 1s, target: 10}]\n" OPS,
     "unknown key 'target' in stages[0]", 1, 25},
    {"stage rate range", "stages: [{duration: 1s, rate: 2e9}]\n" OPS,
     "stage rate (transactions/s): 2e9 is out of range", 1, 31},
    {"stage connections range", "stages: [{duration: 1s, connections: 100001}]\n" OPS,
     "valid 0..100000", 1, 38},
    {"stage ramp choice", "stages: [{duration: 1s, ramp: exponential}]\n" OPS,
     "'exponential' is not one of linear, constant", 1, 31},
    {"stage rate in closed loop", "model: closed\nstages: [{duration: 1s, rate: 10}]\n" OPS,
     "stage rate needs an open-loop scenario", 2, 31},
    {"duration with stages", "duration: 10s\nstages: [{duration: 1s}]\n" OPS,
     "duration: not used with stages", 1, 11},
    {"transactions with stages", "transactions: 10\nstages: [{duration: 1s}]\n" OPS,
     "transactions: not supported with stages", 1, 15},
};

class BadScenario : public ::testing::TestWithParam<BadCase> {};

TEST_P(BadScenario, IsRejectedWithPositionAndReason) {
    const BadCase& c = GetParam();
    const Error e = parse_scenario(c.yaml, "bad.yaml").error();
    ASSERT_FALSE(e.ok()) << c.label << ": accepted";
    EXPECT_EQ(e.code(), ErrorCode::InvalidInput) << c.label;
    const std::string what = e.text();
    EXPECT_NE(e.message().find(c.message), std::string::npos) << c.label << ": got " << what;
    EXPECT_EQ(e.place().rfind("bad.yaml", 0), 0U) << what;
    if (c.line != 0) {
        // The place is the Error's, and the text users see starts with it as it always did.
        const std::string place =
            "bad.yaml:" + std::to_string(c.line) + ":" + std::to_string(c.column);
        EXPECT_EQ(e.place(), place) << c.label << ": " << what;
        EXPECT_EQ(what.rfind(place + ": ", 0), 0U) << what;
    }
}

std::string case_name(const ::testing::TestParamInfo<BadCase>& info) {
    std::string name;
    for (const char* p = info.param.label; *p != '\0'; ++p) {
        name += std::isalnum(static_cast<unsigned char>(*p)) ? *p : '_';
    }
    return name;
}

INSTANTIATE_TEST_SUITE_P(AllErrorPaths, BadScenario, ::testing::ValuesIn(kCases), case_name);

TEST(ScenarioFile, MissingFileIsAnError) {
    const Error e = load_scenario_file("/nonexistent/dir/none.yaml").error();
    EXPECT_EQ(e.code(), ErrorCode::NotFound);
    EXPECT_EQ(e.place(), "/nonexistent/dir/none.yaml");
    EXPECT_EQ(e.text(), "/nonexistent/dir/none.yaml: cannot open the scenario file");
}

}  // namespace
}  // namespace mbstorm::scenario
