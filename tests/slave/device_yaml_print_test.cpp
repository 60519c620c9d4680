// Device description -> YAML -> device description: every key survives the round trip, and a
// default device prints every default.
#include <gtest/gtest.h>

#include <string>

#include "slave/device_yaml.hpp"
#include "slave/device_yaml_print.hpp"

namespace mbstorm::slave::test {
namespace {

std::string error_of_delay(const std::string& delay) {
    return parse_device_yaml("faults: {delay: " + delay + "}\n", "dev.yaml").error().text();
}

// Field-by-field comparison, so a failure names the field that did not survive.
void expect_same(const DeviceDescription& a, const DeviceDescription& b) {
    for (Table t :
         {Table::Coils, Table::DiscreteInputs, Table::InputRegisters, Table::HoldingRegisters}) {
        EXPECT_EQ(a.model.sizes.of(t), b.model.sizes.of(t)) << table_name(t);
    }
    EXPECT_EQ(a.model.file_count, b.model.file_count);
    EXPECT_EQ(a.model.file_records, b.model.file_records);
    EXPECT_EQ(a.model.exception_status, b.model.exception_status);
    EXPECT_EQ(a.model.server_id, b.model.server_id);
    EXPECT_EQ(a.model.run_indicator_on, b.model.run_indicator_on);
    EXPECT_EQ(a.model.track_diagnostics, b.model.track_diagnostics);
    for (unsigned id = 0; id <= 0xFF; ++id) {
        const auto i = static_cast<std::uint8_t>(id);
        EXPECT_EQ(a.model.identity.get(i), b.model.identity.get(i)) << "object " << id;
    }
    EXPECT_EQ(a.shared, b.shared);
    EXPECT_EQ(a.units, b.units);
    EXPECT_EQ(a.unknown_unit, b.unknown_unit);
    EXPECT_EQ(a.broadcast_unit_zero, b.broadcast_unit_zero);
    EXPECT_EQ(a.tls_roles, b.tls_roles);

    ASSERT_EQ(a.init.size(), b.init.size());
    for (std::size_t i = 0; i < a.init.size(); ++i) {
        SCOPED_TRACE("init " + std::to_string(i));
        EXPECT_EQ(a.init[i].table, b.init[i].table);
        EXPECT_EQ(a.init[i].address, b.init[i].address);
        EXPECT_EQ(a.init[i].words, b.init[i].words);
        EXPECT_EQ(a.init[i].units, b.init[i].units);
    }
    ASSERT_EQ(a.read_counters.size(), b.read_counters.size());
    for (std::size_t i = 0; i < a.read_counters.size(); ++i) {
        SCOPED_TRACE("read counter " + std::to_string(i));
        EXPECT_EQ(a.read_counters[i].table, b.read_counters[i].table);
        EXPECT_EQ(a.read_counters[i].address, b.read_counters[i].address);
        EXPECT_EQ(a.read_counters[i].step, b.read_counters[i].step);
        EXPECT_EQ(a.read_counters[i].start, b.read_counters[i].start);
        EXPECT_EQ(a.read_counters[i].units, b.read_counters[i].units);
    }
    ASSERT_EQ(a.simulated.size(), b.simulated.size());
    for (std::size_t i = 0; i < a.simulated.size(); ++i) {
        SCOPED_TRACE("simulated " + std::to_string(i));
        const SimulatedInput& x = a.simulated[i];
        const SimulatedInput& y = b.simulated[i];
        EXPECT_EQ(x.table, y.table);
        EXPECT_EQ(x.address, y.address);
        EXPECT_EQ(x.type, y.type);
        EXPECT_EQ(x.wave, y.wave);
        EXPECT_EQ(x.period_ns, y.period_ns);
        // Exact: the printer writes the shortest text that reads back to the same double.
        EXPECT_EQ(x.amplitude, y.amplitude);
        EXPECT_EQ(x.offset, y.offset);
        EXPECT_EQ(x.phase, y.phase);
        EXPECT_EQ(x.duty, y.duty);
        EXPECT_EQ(x.min, y.min);
        EXPECT_EQ(x.max, y.max);
        EXPECT_EQ(x.step, y.step);
        EXPECT_EQ(x.seed, y.seed);
        EXPECT_EQ(x.units, y.units);
    }
    const FaultConfig& f = a.faults;
    const FaultConfig& g = b.faults;
    EXPECT_EQ(f.delay.kind, g.delay.kind);
    EXPECT_EQ(f.delay.fixed_ns, g.delay.fixed_ns);
    EXPECT_EQ(f.delay.min_ns, g.delay.min_ns);
    EXPECT_EQ(f.delay.max_ns, g.delay.max_ns);
    EXPECT_EQ(f.delay.mean_ns, g.delay.mean_ns);
    EXPECT_EQ(f.stall.duration_ns, g.stall.duration_ns);
    EXPECT_EQ(f.stall.period_ns, g.stall.period_ns);
    EXPECT_EQ(f.exception_rate, g.exception_rate);
    EXPECT_EQ(f.exception_code, g.exception_code);
    EXPECT_EQ(f.drop_rate, g.drop_rate);
    EXPECT_EQ(f.no_answer_rate, g.no_answer_rate);
    EXPECT_EQ(f.seed, g.seed);
}

// Parses `yaml`, prints it, parses the print and checks both descriptions match; printing the
// second one must also give the same text. Returns the printed text.
std::string round_trip(const std::string& yaml) {
    const DeviceDescription first = *parse_device_yaml(yaml, "first.yaml");
    const std::string printed = format_device_yaml(first);
    const Result<DeviceDescription> read_back = parse_device_yaml(printed, "printed.yaml");
    if (!read_back.ok()) {
        ADD_FAILURE() << read_back.error().text() << "\n" << printed;
        return printed;
    }
    const DeviceDescription& second = *read_back;
    SCOPED_TRACE(printed);
    expect_same(first, second);
    EXPECT_EQ(format_device_yaml(second), printed);
    return printed;
}

// Every top-level key, per-unit models, every init form, both counter modes, every waveform.
constexpr const char* kEveryKey = R"(
tables: {coils: 100, discrete_inputs: 200, input_registers: 3000, holding_registers: 40000}
units: [7, 1, 2, "10-12", 200]
unknown_unit: ignore
broadcast_unit_zero: true
diagnostics: false
files: {count: 9, records: 123}
exception_status: 0xA5
server_id: [0, 1, 0xFF, 65]
run_indicator: false
identification:
  vendor_name: 'a "quoted" \back\slash'
  product_code: "null"
  major_minor_revision: "2.0"
  vendor_url: ""
  product_name: "  spaced  "
  model_name: "ünïcode: yes"
  user_application_name: "#not a comment"
  extended: {0x80: "first", 0xFF: "last"}
init:
  - {table: holding_registers, address: 0, values: [1, 2, 3, 0xABCD]}
  - {table: holding_registers, address: 100, value: 0x5555, count: 50, units: [1, 2]}
  - {table: holding_registers, address: 200, type: float32, values: [3.5, -1.25]}
  - {table: holding_registers, address: 210, type: int16, values: [-1, -32768, 32767]}
  - {table: input_registers, address: 0, count: 20, random: {min: 0, max: 1000, seed: 7}}
  - {table: coils, address: 0, values: [1, 0, true, off]}
  - {table: discrete_inputs, address: 5, value: 1, count: 16, units: ["10-12", 7]}
  - {table: input_registers, address: 50, value: 9}
counters:
  - {table: input_registers, address: 1000}
  - {table: holding_registers, address: 1002, mode: read, step: -3, start: -5, units: [200]}
  - {table: input_registers, address: 1001, mode: interval, interval_ms: 0.125, step: 2.5,
     start: -7, type: float32}
  - {address: 1004, mode: interval, interval_ms: 100, type: int16, step: -1, units: [1]}
simulate:
  - {table: input_registers, address: 2000, wave: sine, period_ms: 10000, amplitude: 1000,
     offset: 2000, phase: 0.1}
  - {table: input_registers, address: 2001, wave: ramp, period_ms: 60000.5, amplitude: 100}
  - {table: input_registers, address: 2002, wave: square, period_ms: 2000, amplitude: 1,
     duty: 0.25}
  - {table: holding_registers, address: 2004, wave: sine, period_ms: 5000, amplitude: 50.5,
     type: float32, units: [2, 7]}
  - {table: input_registers, address: 2006, wave: random, period_ms: 0.001, min: -10,
     max: 20.75, seed: 3, type: int16}
  - {table: discrete_inputs, address: 100, wave: square, period_ms: 1000, amplitude: 1}
faults:
  delay: {uniform_ms: [0.5, 2]}
  stall: {duration_ms: 500, every_ms: 30000}
  exception: {rate: 0.001, code: 6}
  drop_rate: 0.0001
  no_answer_rate: 0.3
  seed: 42
tls_roles: {Operator: "1-6,15,16", "Read only": [1, 2, 3, 4]}
)";

TEST(DeviceYamlPrint, EveryKeyRoundTrips) {
    const std::string printed = round_trip(kEveryKey);
    // Per-unit ids come out sorted with consecutive ids folded into ranges.
    EXPECT_NE(printed.find("units: [1, 2, 7, 10-12, 200]"), std::string::npos) << printed;
    EXPECT_NE(printed.find("mode: interval"), std::string::npos) << printed;
    EXPECT_NE(printed.find("interval_ms: 0.125"), std::string::npos) << printed;
    EXPECT_NE(printed.find("period_ms: 60000.5"), std::string::npos) << printed;
    EXPECT_NE(printed.find("0x80: \"first\""), std::string::npos) << printed;
    EXPECT_NE(printed.find("tls_roles: {\"Operator\": \"1-6,15-16\", \"Read only\": \"1-4\"}"),
              std::string::npos)
        << printed;
}

TEST(DeviceYamlPrint, ExampleFileRoundTrips) {
    const DeviceDescription first =
        *load_device_file(MBSTORM_SOURCE_DIR "/scenarios/devices/example-device.yaml");
    const std::string printed = format_device_yaml(first);
    SCOPED_TRACE(printed);
    expect_same(first, *parse_device_yaml(printed, "printed.yaml"));
}

TEST(DeviceYamlPrint, EachDelayKindRoundTrips) {
    for (const char* delay : {"{fixed_ms: 5}", "{fixed_ms: 0}", "{uniform_ms: [0.000001, 1e3]}",
                              "{exponential_mean_ms: 2.5}", "none"}) {
        SCOPED_TRACE(delay);
        round_trip(std::string("faults: {delay: ") + delay + "}\n");
    }
    EXPECT_NE(round_trip("faults: {delay: {exponential_mean_ms: 2.5}}\n")
                  .find("delay: {exponential_mean_ms: 2.5}"),
              std::string::npos);
}

TEST(DeviceYamlPrint, EachFaultSettingRoundTrips) {
    for (const char* faults : {
             "{stall: {duration_ms: 1.5, every_ms: 1000}}", "{exception: {rate: 1}}",
             "{exception: {rate: 0.125, code: 0x7F}}",
             "{drop_rate: 0.5, no_answer_rate: 0.25, exception: {rate: 0.25}}",
             "{no_answer_rate: 0.1}", "{seed: 0}",
             "{seed: 0x4000000000000000}"  // the largest the parser takes,
         }) {
        SCOPED_TRACE(faults);
        round_trip(std::string("faults: ") + faults + "\n");
    }
}

TEST(DeviceYamlPrint, OtherTopLevelSpellingsRoundTrip) {
    round_trip("server_id: \"\"\n");
    round_trip("server_id: 'it''s: fine'\nunits: [0, 255]\n");
    round_trip("tables: {coils: 0, holding_registers: 1}\nfiles: {count: 0, records: 1}\n");
    round_trip("units: [5]\nunknown_unit: gateway_path_unavailable\n");
    round_trip("units: \"0-255\"\n");
}

TEST(DeviceYamlPrint, DefaultDeviceShowsEveryDefault) {
    const std::string printed = round_trip("");
    for (const char* key : {
             "coils: 65536",
             "discrete_inputs: 65536",
             "input_registers: 65536",
             "holding_registers: 65536",
             "units: shared",
             "unknown_unit: gateway_target_failed",
             "broadcast_unit_zero: false",
             "diagnostics: true",
             "files: {count: 4, records: 10000}",
             "exception_status: 0",
             "server_id: \"mbstorm\"",
             "run_indicator: true",
             "vendor_name: \"mbstorm\"",
             "product_code: \"MBSTORM-SLAVE\"",
             "user_application_name: \"mbstorm serve\"",
             "extended: {}",
             "init: []",
             "counters: []",
             "simulate: []",
             "delay: none",
             "stall: {duration_ms: 0, every_ms: 0}",
             "exception: {rate: 0, code: 4}",
             "drop_rate: 0",
             "no_answer_rate: 0",
             "seed: 30789020475683437",  // 0x6d6273746f726d, "mbstorm"
             "tls_roles: {}",
         }) {
        EXPECT_NE(printed.find(key), std::string::npos) << key << " missing in\n" << printed;
    }
}

TEST(DeviceYamlPrint, DelayNoneIsAcceptedAndMeansNoDelay) {
    const DeviceDescription d = *parse_device_yaml("faults: {delay: none}\n");
    EXPECT_EQ(d.faults.delay.kind, DelayConfig::Kind::None);
    EXPECT_FALSE(d.faults.any());
    EXPECT_NE(error_of_delay("fixed").find("faults.delay must be a mapping"), std::string::npos);
}

}  // namespace
}  // namespace mbstorm::slave::test
