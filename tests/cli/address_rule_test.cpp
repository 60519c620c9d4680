// One address rule in every subcommand (codec/address.hpp): run flags, encode, scenarios.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "../support/run_mbstorm.hpp"

using mbstorm::test::run_mbstorm;
using testing::HasSubstr;

namespace {

constexpr const char* kWrongTable =
    "'30001' is an input register reference: read it with 0x04 read_input_registers";

TEST(AddressRule, RunRefusesAReferenceOfAnotherTable) {
    // Used to read holding registers 0-9 without a word.
    auto r = run_mbstorm("run --addr 30001-30010 --fc 3 -d 1s --print-scenario");
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_THAT(r.output, HasSubstr(kWrongTable));
}

TEST(AddressRule, RunAndEncodeReadReferenceNumbersAlike) {
    auto run = run_mbstorm("run --addr 40001-40100 --fc 3 --print-scenario");
    EXPECT_EQ(run.exit_code, 0) << run.output;
    EXPECT_THAT(run.output, HasSubstr("address: 0-99"));
    // encode used to send the literal 40001 (0x9C41).
    EXPECT_EQ(run_mbstorm("encode --fc 3 --addr 40001 --pdu").output, "03 00 00 00 01\n");
    EXPECT_EQ(run_mbstorm("encode --addr 30010 --pdu").output, "04 00 09 00 01\n");
    // The protocol address 40001 is written in hex, everywhere.
    EXPECT_EQ(run_mbstorm("encode --fc 3 --addr 0x9C41 --pdu").output, "03 9C 41 00 01\n");
    auto hex = run_mbstorm("run --addr 0x9C41 --fc 3 --print-scenario");
    EXPECT_THAT(hex.output, HasSubstr("address: 0x9C41"));
}

TEST(AddressRule, EncodeRefusesAReferenceOfAnotherTable) {
    auto r = run_mbstorm("encode --fc 3 --addr 30001");
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_THAT(r.output, HasSubstr(kWrongTable));
    auto ref = run_mbstorm("encode --fc 6 --ref 30001 --value 1");
    EXPECT_EQ(ref.exit_code, 2) << ref.output;
    EXPECT_THAT(ref.output, HasSubstr("--ref '30001' is an input register reference"));
}

TEST(AddressRule, ScenarioRefusesAReferenceOfAnotherTableTheSameWay) {
    const auto path = std::filesystem::temp_directory_path() /
                      ("mbstorm-address-rule-" + std::to_string(::getpid()) + ".yaml");
    {
        std::ofstream f(path);
        f << "operations:\n  - {function: 3, address: 30001-30010}\n";
    }
    auto r = run_mbstorm("run " + path.string() + " --print-scenario");
    std::filesystem::remove(path);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_THAT(r.output, HasSubstr(kWrongTable));
}

TEST(AddressRule, HelpStatesTheRuleOnce) {
    for (const char* cmd : {"run --help", "encode --help"}) {
        auto r = run_mbstorm(cmd);
        EXPECT_THAT(r.output, HasSubstr("5-6 digits starting 0/1/3/4 are always reference")) << cmd;
    }
}

}  // namespace
