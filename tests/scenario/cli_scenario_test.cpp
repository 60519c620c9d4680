// `mbstorm run FILE` end to end through the binary: exit codes 0 / 1 / 2, overrides,
// --print-scenario and --junit. Runs are one second or less, loopback only.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include "../support/run_mbstorm.hpp"
#include "must_parse.hpp"
#include "scenario/scenario.hpp"
#include "slave/device_yaml_print.hpp"

namespace {

using mbstorm::test::run_mbstorm;

std::string write_temp(const std::string& name, const std::string& text) {
    const std::string path = ::testing::TempDir() + "/" + name;
    std::ofstream(path) << text;
    return path;
}

std::string read_file(const std::string& path) {
    std::ifstream in(path);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

const std::string kLibrary = std::string(MBSTORM_SOURCE_DIR) + "/scenarios/";
const std::string kSmall = " -q --threads 1 --slave-threads 1 -c 2 --depth 2 ";

TEST(CliScenario, PassingThresholdsExitZero) {
    const auto r = run_mbstorm("run " + kLibrary + "quickstart.yaml -d 500ms" + kSmall);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("Thresholds  all passed"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("embedded reference slave"), std::string::npos);
}

TEST(CliScenario, BreachedThresholdExitsOneAndJunitShowsIt) {
    const std::string file = write_temp("breach.yaml", R"(
duration: 300ms
operations: [{function: 3, address: 0-9}]
thresholds:
  - errors == 0
  - throughput > 1000M/s
)");
    const std::string junit = ::testing::TempDir() + "/breach.xml";
    const auto r = run_mbstorm("run " + file + kSmall + "--junit " + junit);
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find("FAIL  throughput > 1000M/s"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("1 of 2 thresholds breached"), std::string::npos) << r.output;
    const std::string xml = read_file(junit);
    EXPECT_NE(xml.find("tests=\"2\" failures=\"1\""), std::string::npos) << xml;
    EXPECT_NE(xml.find("name=\"throughput &gt; 1000M/s\""), std::string::npos) << xml;
}

TEST(CliScenario, JunitIsWrittenWhenTheRunCannotStart) {
    // Port 1 on loopback refuses: no transaction is ever sent, and CI still gets a JUnit file
    // whose failing case says why.
    const std::string junit = ::testing::TempDir() + "/refused.xml";
    std::remove(junit.c_str());
    const auto r = run_mbstorm("run " + kLibrary + "quickstart.yaml --target 127.0.0.1:1" + kSmall +
                               "-d 500ms --junit " + junit);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find("wrote JUnit XML " + junit), std::string::npos) << r.output;
    const std::string xml = read_file(junit);
    EXPECT_NE(xml.find("<failure"), std::string::npos) << xml;
}

TEST(CliScenario, InvalidFileExitsTwoWithPosition) {
    const std::string file =
        write_temp("invalid.yaml", "operations:\n  - {function: 3, quantity: 200}\n");
    const auto r = run_mbstorm("run " + file);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(file + ":2:29: quantity for 0x03 read_holding_registers: 200 is out of "
                                   "range (valid 1..125)"),
              std::string::npos)
        << r.output;
}

TEST(CliScenario, PrintScenarioAppliesOverridesAndSendsNothing) {
    const auto r = run_mbstorm("run " + kLibrary +
                               "ci-gate.yaml --print-scenario -c 3 --target 127.0.0.1:1 -d 2s");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("connections: 3"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("target: 127.0.0.1:1"), std::string::npos);
    EXPECT_NE(r.output.find("duration: 2s"), std::string::npos);
    EXPECT_NE(r.output.find("address: 0-99"), std::string::npos);  // 40001-40100 resolved
    EXPECT_NE(r.output.find("- \"p99 < 50ms\""), std::string::npos);
    EXPECT_EQ(r.output.find("Throughput"), std::string::npos);  // no run happened

    const auto flags_only = run_mbstorm("run --print-scenario --fc 4 -c 5");
    EXPECT_EQ(flags_only.exit_code, 0) << flags_only.output;
    EXPECT_NE(flags_only.output.find("function: read_input_registers"), std::string::npos)
        << flags_only.output;
    EXPECT_NE(flags_only.output.find("connections: 5"), std::string::npos);
}

// quickstart.yaml has no `slave:` key: the printout shows the embedded slave's defaults, and
// the printout is itself a scenario that prints the same again.
TEST(CliScenario, PrintScenarioShowsSlaveDefaultsAndRoundTrips) {
    const auto r = run_mbstorm("run " + kLibrary + "quickstart.yaml --print-scenario");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    for (const char* key : {"slave:", "units: shared", "unknown_unit: gateway_target_failed",
                            "coils: 65536", "server_id: \"mbstorm\"", "init: []", "simulate: []",
                            "delay: none", "exception: {rate: 0, code: 4}", "drop_rate: 0"}) {
        EXPECT_NE(r.output.find(key), std::string::npos) << key << " missing in\n" << r.output;
    }

    const std::string path = write_temp("quickstart-printed.yaml", r.output);
    const mbstorm::scenario::Scenario parsed = mbstorm::scenario::must_load(path);
    EXPECT_EQ(mbstorm::slave::format_device_yaml(parsed.slave),
              mbstorm::slave::format_device_yaml(mbstorm::slave::DeviceDescription{}));
    EXPECT_EQ(parsed.name, "quickstart");

    const auto again = run_mbstorm("run " + path + " --print-scenario");
    ASSERT_EQ(again.exit_code, 0) << again.output;
    // Only the first line (it names the source file) may differ.
    const auto body = [](const std::string& text) { return text.substr(text.find('\n')); };
    EXPECT_EQ(body(again.output), body(r.output));
}

TEST(CliScenario, UsageErrorsExitTwo) {
    EXPECT_EQ(run_mbstorm("run " + kLibrary + "quickstart.yaml --fc 4").exit_code, 2);
    EXPECT_EQ(run_mbstorm("run --junit x.xml -d 1s").exit_code, 2);
    EXPECT_EQ(run_mbstorm("run /nonexistent/scenario.yaml").exit_code, 2);
    const auto bad_target = run_mbstorm("run " + kLibrary + "quickstart.yaml --target nowhere:");
    EXPECT_EQ(bad_target.exit_code, 2);
    EXPECT_NE(bad_target.output.find("port 502 if omitted"), std::string::npos)
        << bad_target.output;
}

TEST(CliScenario, StagedRunReportsStagesInJson) {
    const std::string json = ::testing::TempDir() + "/staged.json";
    const auto r = run_mbstorm("run " + kLibrary + "ramp-to-saturation.yaml -d 600ms" + kSmall +
                               "--json " + json);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("Per stage"), std::string::npos) << r.output;
    const std::string text = read_file(json);
    EXPECT_NE(text.find("\"200k\""), std::string::npos) << text.substr(0, 2000);
}

}  // namespace
