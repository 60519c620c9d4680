// One rule for function codes (issue #12): every --fc reads names, 0x hex and decimal alike, and
// every output shows "0x10 write_multiple_registers".
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "../support/run_mbstorm.hpp"

using mbstorm::test::run_mbstorm;
using testing::HasSubstr;
using testing::Not;

namespace {

constexpr const char* kForms =
    "a name (write_multiple_registers), hex with 0x (0x10) or decimal (16)";

TEST(FunctionCodeFlags, RunReadsNamesHexAndDecimalAlike) {
    for (const char* fc : {"write_multiple_registers", "0x10", "16"}) {
        auto r = run_mbstorm(std::string("run --fc ") + fc + " --addr 0 --print-scenario");
        EXPECT_EQ(r.exit_code, 0) << fc << "\n" << r.output;
        EXPECT_THAT(r.output, HasSubstr("function: write_multiple_registers")) << fc;
    }
    auto mask = run_mbstorm("run --fc 0x16 --addr 0 --print-scenario");
    EXPECT_THAT(mask.output, HasSubstr("function: mask_write_register"));
}

TEST(FunctionCodeFlags, RunAgainstTheEmbeddedSlaveLabelsTheOperation) {
    for (const char* fc : {"write_multiple_registers", "0x10"}) {
        auto r = run_mbstorm(std::string("run --fc ") + fc + " --addr 0 -c 1 -d 1s", 60);
        EXPECT_EQ(r.exit_code, 0) << fc << "\n" << r.output;
        EXPECT_THAT(r.output, HasSubstr("  0x10 write_multiple_registers ")) << r.output;
    }
}

TEST(FunctionCodeFlags, RefusalsNameTheValueAndTheForms) {
    for (const char* cmd :
         {"run --fc 0x80 --print-scenario", "run --fc write_regs --print-scenario",
          "encode --fc 16h --addr 0", "write --target 127.0.0.1:1 --fc 1O --addr 0 1"}) {
        auto r = run_mbstorm(cmd, 30);
        EXPECT_EQ(r.exit_code, 2) << cmd << "\n" << r.output;
        EXPECT_THAT(r.output, HasSubstr(kForms)) << cmd;
    }
}

TEST(FunctionCodeFlags, EncodeAndWriteAcceptTheSameForms) {
    EXPECT_EQ(run_mbstorm("encode --fc 0x10 --addr 0 --values 7 --pdu").output,
              run_mbstorm("encode --fc write_multiple_registers --addr 0 --values 7 --pdu").output);
    EXPECT_EQ(run_mbstorm("encode --fc 0x10 --addr 0 --values 7 --pdu").output,
              run_mbstorm("encode --fc 16 --addr 0 --values 7 --pdu").output);
    // 010 is decimal ten, not octal eight.
    EXPECT_EQ(run_mbstorm("encode --fc 010 --addr 0 --quantity 1 --pdu").exit_code, 2);
}

TEST(FunctionCodeFlags, DecodeShowsTheFunctionCodeInHexWithItsName) {
    auto r = run_mbstorm("decode --pdu 10 00 00 00 01 02 00 07");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_THAT(r.output, HasSubstr("0x10 write_multiple_registers")) << r.output;
    EXPECT_THAT(r.output, Not(HasSubstr(" 16 write_multiple_registers"))) << r.output;
}

TEST(FunctionCodeFlags, HelpTextsNameFunctionsInHexAndStateTheFormsOnce) {
    for (const char* cmd : {"run --help", "encode --help", "write --help"}) {
        auto r = run_mbstorm(cmd);
        EXPECT_THAT(r.output, HasSubstr(kForms)) << cmd;
        EXPECT_THAT(r.output, Not(HasSubstr("FC05/06/16"))) << cmd;
    }
    EXPECT_THAT(run_mbstorm("run --help").output, HasSubstr("0x16 mask_write_register"));
}

}  // namespace
