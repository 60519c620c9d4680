// Device descriptions from YAML: every section, the example file, and error messages with lines.
#include <gtest/gtest.h>

#include <bit>
#include <cstdio>
#include <fstream>
#include <string>

#include <yaml-cpp/yaml.h>

#include "slave/device_yaml.hpp"
#include "slave_test_support.hpp"

namespace mbstorm::slave::test {
namespace {

// Runs the parser and returns the error message ("" when it parsed).
std::string error_of(const std::string& yaml) {
    const Result<DeviceDescription> d = parse_device_yaml(yaml, "dev.yaml");
    if (!d.ok()) {
        EXPECT_EQ(d.error().code(), ErrorCode::InvalidInput);
    }
    return d.error().text();
}

TEST(DeviceYaml, EmptyDocumentIsTheDefaultDevice) {
    const DeviceDescription d = *parse_device_yaml("", "empty.yaml");
    EXPECT_TRUE(d.shared);
    EXPECT_EQ(d.model.sizes.holding_registers, 65536u);
    EXPECT_FALSE(d.faults.any());
}

TEST(DeviceYaml, ExampleFileLoadsAndBuilds) {
    const DeviceDescription d = *load_device_file(std::string(MBSTORM_SOURCE_DIR) +
                                                  "/scenarios/devices/example-device.yaml");
    EXPECT_FALSE(d.shared);
    EXPECT_EQ(d.units, (std::vector<std::uint8_t>{1, 2, 10, 11, 12}));
    EXPECT_EQ(d.model.sizes.coils, 10000u);
    EXPECT_EQ(d.model.identity.get(0x80), "serial 0001");
    EXPECT_EQ(d.faults.delay.kind, DelayConfig::Kind::Uniform);
    EXPECT_EQ(d.faults.delay.min_ns, 500'000u);
    EXPECT_EQ(d.faults.stall.period_ns, 30'000'000'000u);
    EXPECT_DOUBLE_EQ(d.faults.exception_rate, 0.001);
    EXPECT_EQ(d.faults.seed, 42u);

    const UnitModels units = build_units(d);
    EXPECT_EQ(units.model_count(), 5u);
    DataModel& u1 = *units.find(1);
    EXPECT_EQ(u1.holding_registers().get(3), 0xABCD);
    EXPECT_EQ(u1.holding_registers().get(149), 0x5555);
    const auto f = std::bit_cast<float>((std::uint32_t{u1.holding_registers().get(200)} << 16) |
                                        u1.holding_registers().get(201));
    EXPECT_FLOAT_EQ(f, 3.5f);
    EXPECT_TRUE(u1.coils().get(2));
    EXPECT_FALSE(u1.discrete_inputs().get(0));  // unit 2 only
    EXPECT_TRUE(units.find(2)->discrete_inputs().get(15));
    // FIFO from the init entry.
    const Reply fifo = call(u1, Pdu(0x18).u16(300));
    EXPECT_EQ(fifo.decoded.fifo_count, 3);
    // Read counter: +1 before each read; the other read counter starts at 1000, step 10.
    EXPECT_EQ(call(u1, Pdu(0x04).u16(1000).u16(1)).reg(0), 1);
    EXPECT_EQ(call(u1, Pdu(0x04).u16(1000).u16(1)).reg(0), 2);
    EXPECT_EQ(call(u1, Pdu(0x03).u16(1002).u16(1)).reg(0), 1010);
    // Identification and server id reach the handler.
    EXPECT_EQ(call(u1, Pdu(0x11)).bytes[1], 13);  // "mbstorm-demo" + run indicator
    EXPECT_EQ(d.simulated.size(), 7u);            // 6 simulate + 1 interval counter
}

TEST(DeviceYaml, RandomInitIsDeterministicAndInRange) {
    const char* yaml =
        "init: [{table: input_registers, address: 0, count: 500, random: {min: 10, max: 20, seed: "
        "5}}]";
    const UnitModels a = build_units(*parse_device_yaml(yaml));
    const UnitModels b = build_units(*parse_device_yaml(yaml));
    bool saw_min = false, saw_max = false;
    for (std::uint16_t i = 0; i < 500; ++i) {
        const auto v = a.model_at(0).input_registers().get(i);
        ASSERT_GE(v, 10);
        ASSERT_LE(v, 20);
        saw_min |= v == 10;
        saw_max |= v == 20;
        EXPECT_EQ(v, b.model_at(0).input_registers().get(i));
    }
    EXPECT_TRUE(saw_min && saw_max);
}

TEST(DeviceYaml, Int16AndHexValues) {
    const UnitModels u =
        build_units(*parse_device_yaml("init:\n  - {table: holding_registers, address: 0, type: "
                                       "int16, values: [-1, -32768, 0x10]}\n"));
    EXPECT_EQ(u.model_at(0).holding_registers().get(0), 0xFFFF);
    EXPECT_EQ(u.model_at(0).holding_registers().get(1), 0x8000);
    EXPECT_EQ(u.model_at(0).holding_registers().get(2), 0x0010);
}

TEST(DeviceYaml, FaultSettings) {
    const DeviceDescription d = *parse_device_yaml(R"(
faults:
  delay: {exponential_mean_ms: 2.5}
  exception: {rate: 0.25, code: 6}
  drop_rate: 0.1
  no_answer_rate: 0.05
)");
    EXPECT_EQ(d.faults.delay.kind, DelayConfig::Kind::Exponential);
    EXPECT_EQ(d.faults.delay.mean_ns, 2'500'000u);
    EXPECT_EQ(d.faults.exception_code, codec::ExceptionCode::ServerDeviceBusy);
    EXPECT_DOUBLE_EQ(d.faults.drop_rate, 0.1);
    EXPECT_EQ(parse_device_yaml("faults: {delay: {fixed_ms: 5}}")->faults.delay.fixed_ns,
              5'000'000u);
}

TEST(DeviceYaml, TlsRolesListFunctionCodesPerRoleLikeTheTlsRoleFlag) {
    const DeviceDescription d = *parse_device_yaml(R"(
tls_roles:
  Operator: "1-6,15,16"
  Viewer: [1, 2, 0x03, "4"]
)");
    ASSERT_EQ(d.tls_roles.size(), 2u);
    EXPECT_EQ(d.tls_roles[0].first, "Operator");
    EXPECT_EQ(codec::format_function_set(d.tls_roles[0].second), "1-6,15-16");
    EXPECT_EQ(d.tls_roles[1].first, "Viewer");
    EXPECT_EQ(codec::format_function_set(d.tls_roles[1].second), "1-4");
    EXPECT_TRUE(parse_device_yaml("")->tls_roles.empty());
    std::string e = error_of("tls_roles:\n  Operator: \"1-6,300\"\n");
    EXPECT_NE(e.find("dev.yaml:2:13: tls_roles.Operator: bad function code or range '300'"),
              std::string::npos)
        << e;
    e = error_of("tls_roles: [Operator]\n");
    EXPECT_NE(e.find("tls_roles maps each role"), std::string::npos) << e;
    e = error_of("tls_roles: {Viewer: \"\"}\n");
    EXPECT_NE(e.find("empty list"), std::string::npos) << e;
}

TEST(DeviceYaml, DuplicateKeysAreRejectedAndUnknownKeysListTheValidOnes) {
    std::string e = error_of("tables:\n  coils: 10\n  coils: 20\n");
    EXPECT_NE(e.find("dev.yaml:3:3: duplicate key 'coils' in tables"), std::string::npos) << e;
    e = error_of("faults: {stall: {duration_ms: 1, every: 2}}\n");
    EXPECT_NE(e.find("unknown key 'every' in faults.stall (valid keys: duration_ms, every_ms)"),
              std::string::npos)
        << e;
    e = error_of("identification: {vendor: x}\n");
    EXPECT_NE(e.find("valid keys: vendor_name, "), std::string::npos) << e;
    EXPECT_NE(e.find(", extended)"), std::string::npos) << e;
}

TEST(DeviceYaml, IntegersMayBeBinary) {
    EXPECT_EQ(parse_device_yaml("exception_status: 0b1010")->model.exception_status, 10);
}

TEST(DeviceYaml, ErrorsCarryLineAndColumn) {
    // Unknown key: line 4, column 20 (where "adress" starts).
    std::string e =
        error_of("tables:\n  coils: 10\ninit:\n  - {table: coils, adress: 0, value: 1}\n");
    EXPECT_NE(e.find("dev.yaml:4:20: unknown key 'adress' in init entry"), std::string::npos) << e;
    e = error_of("tables:\n  coils: 70000\n");
    EXPECT_NE(e.find("dev.yaml:2:10:"), std::string::npos) << e;
    EXPECT_NE(e.find("out of range (valid 0..65536)"), std::string::npos) << e;
    // YAML syntax errors come from yaml-cpp's own marks.
    e = error_of("tables: {coils: 10\n");
    EXPECT_EQ(e.rfind("dev.yaml:", 0), 0u) << e;
    EXPECT_NE(e.find(":2:"), std::string::npos) << e;
    e = error_of("units: shared\nfoo: 1\n");
    EXPECT_EQ(e.rfind("dev.yaml:2:1: ", 0), 0u) << e;
    // Embedded in another document, the device's error keeps its line and column.
    try {
        parse_device_node(YAML::Load("units: shared\nfoo: 1\n"), "x.yaml");
        FAIL();
    } catch (const DeviceYamlError& err) {
        EXPECT_EQ(err.line(), 2);
        EXPECT_EQ(err.column(), 1);
    }
}

// Device files follow the address rule of every subcommand (codec/address.hpp).
TEST(DeviceYaml, AddressesFollowTheOneRule) {
    const DeviceDescription d = *parse_device_yaml(
        "init:\n"
        "  - {table: holding_registers, address: 40101, value: 1}\n"
        "  - {table: holding_registers, address: 0x9C41, value: 2}\n"
        "counters: [{table: input_registers, address: 30011}]\n",
        "dev.yaml");
    ASSERT_EQ(d.init.size(), 2u);
    EXPECT_EQ(d.init[0].address, 100);
    EXPECT_EQ(d.init[1].address, 0x9C41);
    ASSERT_EQ(d.read_counters.size(), 1u);
    EXPECT_EQ(d.read_counters[0].address, 10);
    // Used to store at holding register 30001.
    EXPECT_NE(error_of("init: [{table: holding_registers, address: 30001, value: 1}]")
                  .find("'30001' is an input register reference: read it with 0x04 "
                        "read_input_registers"),
              std::string::npos);
    EXPECT_NE(error_of("init: [{table: coils, address: 0-3, value: 1}]").find("is a range"),
              std::string::npos);
}

TEST(DeviceYaml, RangeAndConsistencyErrors) {
    EXPECT_NE(error_of("tables: {holding_registers: 10}\ninit: [{table: holding_registers, "
                       "address: 8, values: [1, 2, 3]}]")
                  .find("does not fit holding_registers (size 10)"),
              std::string::npos);
    EXPECT_NE(error_of("init: [{table: holding_registers, address: 0, values: [70000]}]")
                  .find("uint16 value"),
              std::string::npos);
    EXPECT_NE(error_of("init: [{table: coils, address: 0, values: [2]}]").find("bit value"),
              std::string::npos);
    EXPECT_NE(error_of("init: [{table: coils, address: 0}]").find("exactly one of"),
              std::string::npos);
    EXPECT_NE(error_of("init: [{table: tables, address: 0, value: 1}]").find("unknown table"),
              std::string::npos);
    EXPECT_NE(error_of("init: [{table: coils, address: 0, value: 1, units: [1]}]").find("per-unit"),
              std::string::npos);
    EXPECT_NE(error_of("units: [1]\ninit: [{table: coils, address: 0, value: 1, units: [3]}]")
                  .find("unit 3 is not in"),
              std::string::npos);
    EXPECT_NE(error_of("faults: {drop_rate: 0.7, no_answer_rate: 0.7}").find("add up"),
              std::string::npos);
    EXPECT_NE(error_of("faults: {delay: {fixed_ms: 1, uniform_ms: [1, 2]}}").find("exactly one"),
              std::string::npos);
    EXPECT_NE(error_of("simulate: [{table: input_registers, address: 0, wave: saw, period_ms: 10}]")
                  .find("unknown wave"),
              std::string::npos);
    EXPECT_NE(error_of("simulate: [{table: input_registers, address: 65535, wave: sine, period_ms: "
                       "10, type: float32}]")
                  .find("does not fit"),
              std::string::npos);
    EXPECT_NE(error_of("counters: [{address: 1, mode: interval}]").find("interval_ms"),
              std::string::npos);
    EXPECT_NE(error_of("identification: {vendor_name: " + std::string(245, 'x') + "}")
                  .find("longer than 244"),
              std::string::npos);
    EXPECT_NE(error_of("broadcast_unit_zero: maybe").find("true or false"), std::string::npos);
    EXPECT_NE(error_of("unknown_unit: shrug").find("unknown_unit must be"), std::string::npos);
    EXPECT_NE(error_of("tables: [1, 2]").find("tables must be a mapping"), std::string::npos);
}

TEST(DeviceYaml, MissingFileIsAClearError) {
    const Result<DeviceDescription> d = load_device_file("/nonexistent/device.yaml");
    EXPECT_EQ(d.error().code(), ErrorCode::Io);
    EXPECT_EQ(d.error().text(), "/nonexistent/device.yaml: cannot open the device file");
}

// YAML aliases repeat an init entry for a few bytes each: a 1.4 KB file of 20 aliased entries
// over 247 units asked for 340 million writes (3 s of start-up; 21 KB took 30 s). Refused, as
// is more than four tables' worth of values; every register of every unit written once, the
// most a description needs, still loads.
TEST(DeviceYaml, InitWorkIsBoundedWhateverTheAliases) {
    std::string all_units = "units: [1-247]\n";
    std::string aliased = all_units +
                          "init:\n  - &e {table: holding_registers, address: 0, value: 7, "
                          "count: 65536}\n";
    for (int i = 0; i < 20; ++i) aliased += "  - *e\n";
    std::string e = error_of(aliased);
    EXPECT_NE(e.find("init entry 5: init writes more than 67108864 values"), std::string::npos)
        << e;
    std::string shared = "init:\n  - &e {table: coils, address: 0, value: 1, count: 65536}\n";
    for (int i = 0; i < 20; ++i) shared += "  - *e\n";
    e = error_of(shared);
    EXPECT_NE(e.find("init entry 17: init holds more than 1048576 values"), std::string::npos) << e;
    // A unit named twice in an entry's filter is one unit's work.
    std::string repeated = all_units + "init:\n";
    for (const char* t : {"coils", "discrete_inputs", "input_registers", "holding_registers"})
        repeated += std::string("  - {table: ") + t +
                    ", address: 0, value: 1, count: 65536, units: [1-247, 1-247, 1-247]}\n";
    EXPECT_EQ(error_of(repeated), "");
    const DeviceDescription d = *parse_device_yaml(repeated, "dev.yaml");
    ASSERT_EQ(d.init.size(), 4u);
    EXPECT_EQ(d.init[0].units.size(), 247u);
}

TEST(DeviceYaml, AFileLargerThan16MiBIsNotReadWhole) {
    const std::string path = ::testing::TempDir() + "/huge_device.yaml";
    {
        std::ofstream out(path, std::ios::binary);
        const std::string comment = "# " + std::string(1022, 'x') + "\n";
        for (int i = 0; i < 17 * 1024; ++i) out << comment;
    }
    const Result<DeviceDescription> d = load_device_file(path);
    EXPECT_EQ(d.error().code(), ErrorCode::InvalidInput);
    EXPECT_NE(d.error().text().find("larger than 16 MiB"), std::string::npos) << d.error().text();
    std::remove(path.c_str());
}

TEST(DeviceYaml, PolicySettingsReachTheUnits) {
    const UnitModels u = build_units(*parse_device_yaml(
        "units: [1, 5]\nunknown_unit: ignore\nbroadcast_unit_zero: yes\ndiagnostics: false\n"));
    EXPECT_EQ(u.unknown_unit_policy, UnknownUnitPolicy::Ignore);
    EXPECT_TRUE(u.broadcast_unit_zero);
    EXPECT_FALSE(u.find(5)->track_diagnostics());
    EXPECT_EQ(u.find(2), nullptr);
}

}  // namespace
}  // namespace mbstorm::slave::test
