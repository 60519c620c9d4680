// `mbstorm read` / `mbstorm write` end to end against `mbstorm serve`.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include "../support/run_mbstorm.hpp"
#include "../support/target_process.hpp"

using mbstorm::test::run_mbstorm;
using mbstorm::test::start_reference_slave;
using mbstorm::test::Target;
using testing::HasSubstr;

namespace {

class ReadWrite : public testing::Test {
  protected:
    void SetUp() override {
        // Small tables, so that reading past their end draws an exception.
        device_ = std::filesystem::temp_directory_path() /
                  ("mbstorm-read-write-" + std::to_string(::getpid()) + ".yaml");
        std::ofstream(device_) << "tables: {coils: 32, discrete_inputs: 32, input_registers: 16, "
                                  "holding_registers: 200}\n"
                                  "init:\n"
                                  "  - {table: input_registers, address: 30003, values: [7, 8]}\n";
        target_ = start_reference_slave(server_, {"--device", device_.string()});
        ASSERT_FALSE(target_.empty()) << "mbstorm serve did not start";
    }
    void TearDown() override {
        server_.reset();
        std::filesystem::remove(device_);
    }
    // "read ARGS" -> "read --target T ARGS" (before any "--" that ends the options).
    mbstorm::test::CommandResult io(const std::string& args) {
        const auto space = args.find(' ');
        std::string cmd = args.substr(0, space);
        cmd.append(" --target ").append(target_).append(args.substr(space));
        return run_mbstorm(cmd, 30);
    }

    std::filesystem::path device_;
    std::unique_ptr<Target> server_;
    std::string target_;
};

TEST_F(ReadWrite, WrittenValuesReadBackInEveryTypeAndOrder) {
    auto w = io("write --addr 40101 --type f32 --order CDAB 3.5 -1.25");
    ASSERT_EQ(w.exit_code, 0) << w.output;
    EXPECT_THAT(w.output, HasSubstr("wrote 4 register(s) at address 100 of unit 1 (0x10 "
                                    "write_multiple_registers)"));
    auto f = io("read --addr 40101 --quantity 2 --type f32 --order CDAB");
    EXPECT_EQ(f.exit_code, 0) << f.output;
    EXPECT_EQ(f.output, "[100]: 3.5\n[102]: -1.25\n");
    // 3.5f is 0x40600000: low word first.
    EXPECT_EQ(io("read --addr 100 --quantity 2").output, "[100]: 0\n[101]: 16480\n");

    ASSERT_EQ(io("write --addr 0x10 --type i32 -- -2").exit_code, 0);
    EXPECT_EQ(io("read --addr 16 --type i32").output, "[16]: -2\n");
    EXPECT_EQ(io("read --addr 16 --type i16 --quantity 2").output, "[16]: -1\n[17]: -2\n");
    ASSERT_EQ(io("write --addr 20 --type f64 --order DCBA 0.1").exit_code, 0);
    EXPECT_EQ(io("read --addr 20 --type f64 --order DCBA").output, "[20]: 0.1\n");
    ASSERT_EQ(io("write --addr 30 --type string pump-7").exit_code, 0);
    EXPECT_EQ(io("read --addr 30 --type string --quantity 6").output, "[30]: pump-7\n");
    EXPECT_EQ(io("read --addr 30 --type bits").output, "[30]: 0111000001110101\n");

    ASSERT_EQ(io("write --addr 00003 1 0 1").exit_code, 0);  // coil references
    EXPECT_EQ(io("read --table coils --addr 2 --quantity 4").output,
              "[2]: 1\n[3]: 0\n[4]: 1\n[5]: 0\n");
    EXPECT_EQ(io("read --addr 30003 --quantity 2").output, "[2]: 7\n[3]: 8\n");
}

TEST_F(ReadWrite, Float32ReadsBackAsTheShortestTextOfTheFloat) {
    // 0.1f is 0.100000001490116...: shown as the float it is, not widened to a double first.
    ASSERT_EQ(io("write --addr 40 --type f32 0.1 23.7").exit_code, 0);
    EXPECT_EQ(io("read --addr 40 --quantity 2 --type f32").output, "[40]: 0.1\n[42]: 23.7\n");
    auto j = io("read --addr 40 --quantity 2 --type f32 --json");
    EXPECT_EQ(j.exit_code, 0) << j.output;
    EXPECT_THAT(j.output, HasSubstr("\"values\":[{\"address\":40,\"value\":0.1},"
                                    "{\"address\":42,\"value\":23.7}]"));
}

TEST_F(ReadWrite, SingleValuesUseTheSingleWriteFunctionsUnlessTold) {
    auto one = io("write --addr 5 42");
    EXPECT_THAT(one.output, HasSubstr("0x06 write_single_register"));
    auto forced = io("write --addr 5 --fc 0x10 43");
    EXPECT_THAT(forced.output, HasSubstr("0x10 write_multiple_registers"));
    EXPECT_EQ(io("read --addr 5").output, "[5]: 43\n");
    auto coil = io("write --table coils --addr 1 on");
    EXPECT_THAT(coil.output, HasSubstr("0x05 write_single_coil"));
}

TEST_F(ReadWrite, ExceptionIsNamedAndExitsNonZero) {
    auto r = io("read --addr 30020");
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_THAT(r.output, HasSubstr("unit 1 answered exception 02 ILLEGAL DATA ADDRESS to 0x04 "
                                    "read_input_registers at address 19"));
    auto j = io("read --addr 250 --json");
    EXPECT_EQ(j.exit_code, 1) << j.output;
    EXPECT_THAT(j.output,
                HasSubstr("\"exception\":{\"code\":2,\"name\":\"ILLEGAL DATA ADDRESS\"}"));
}

TEST_F(ReadWrite, JsonAndRepeatedPolls) {
    ASSERT_EQ(io("write --addr 7 --type u32 70000").exit_code, 0);
    auto r = io("read --addr 7 --type u32 --json -n 3 --interval 10ms");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 3) << r.output;
    EXPECT_THAT(r.output, HasSubstr("\"poll\":3"));
    EXPECT_THAT(r.output, HasSubstr("\"values\":[{\"address\":7,\"value\":70000}]"));
    EXPECT_THAT(r.output, HasSubstr("\"registers\":[1,4464]"));
    EXPECT_THAT(r.output, HasSubstr("\"function\":\"0x03 read_holding_registers\""));
}

// For mbpoll and modpoll users (issue #29): each value's registers in hex as they came, the
// values numbered from 1 as mbpoll numbers them, and each poll's time.
TEST_F(ReadWrite, HexOneBasedNumbersAndTimestamps) {
    ASSERT_EQ(io("write --addr 100 --type f32 3.5").exit_code, 0);
    EXPECT_EQ(io("read --addr 100 --type f32 --hex").output, "[100]: 3.5 0x40600000\n");
    EXPECT_EQ(io("read --addr 40101 --quantity 2 --hex --one-based").output,
              "[101]: 16480 0x4060\n[102]: 0 0x0000\n");
    auto t = io("read --addr 100 -n 2 --interval 10ms --timestamps");
    EXPECT_EQ(t.exit_code, 0) << t.output;
    EXPECT_THAT(t.output, testing::MatchesRegex("-- 20[0-9][0-9]-[01][0-9]-[0-3][0-9]T[0-2][0-9]:"
                                                "[0-5][0-9]:[0-6][0-9][.][0-9][0-9][0-9]Z poll 1\n"
                                                "\\[100\\]: 16480\n\n"
                                                "-- [-0-9T:.]+Z poll 2\n\\[100\\]: 16480\n"))
        << t.output;
    auto j = io("read --addr 100 --quantity 2 --json --hex --one-based --timestamps");
    EXPECT_EQ(j.exit_code, 0) << j.output;
    EXPECT_THAT(j.output, HasSubstr("\"values\":[{\"address\":100,\"hex\":\"0x4060\",\"reference\":"
                                    "101,\"value\":16480},"));
    EXPECT_THAT(j.output, testing::ContainsRegex("\"time\":\"20[0-9-]+T[0-9:.]+Z\""));
    auto bits = io("read --table coils --addr 0 --hex");
    EXPECT_EQ(bits.exit_code, 2) << bits.output;
    EXPECT_THAT(bits.output, HasSubstr("--hex shows registers in hex; coils hold single bits"));
}

// -q (now --quiet elsewhere) and --count (now -n/--transactions) keep their old meaning here.
TEST_F(ReadWrite, OldSpellingsOfQuantityAndCountStillWorkWithAWarning) {
    ASSERT_EQ(io("write --addr 50 1 2 3").exit_code, 0);
    auto r = io("read --addr 50 -q 3 --count 2 --interval 10ms");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_THAT(r.output, HasSubstr("mbstorm read: -q is deprecated, use --quantity\n"));
    EXPECT_THAT(r.output, HasSubstr("mbstorm read: --count is deprecated, use --transactions\n"));
    EXPECT_THAT(r.output, HasSubstr("[50]: 1\n[51]: 2\n[52]: 3\n"));
    std::size_t polls = 0;
    for (auto at = r.output.find("[52]"); at != std::string::npos;
         at = r.output.find("[52]", at + 1))
        ++polls;
    EXPECT_EQ(polls, 2u) << r.output;
}

// --addr FIRST-LAST, as --help says: the range is what is read (reference numbers too);
// with --quantity besides, or a range not whole values of --type, it is refused.
TEST_F(ReadWrite, AnAddressRangeSaysHowManyToRead) {
    auto w = io("write --addr 40011 1 2 3 4");
    ASSERT_EQ(w.exit_code, 0) << w.output;
    auto r = io("read --addr 40011-40014");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(r.output, "[10]: 1\n[11]: 2\n[12]: 3\n[13]: 4\n");
    auto u32 = io("read --addr 10-13 --type u32");
    EXPECT_EQ(u32.exit_code, 0) << u32.output;
    EXPECT_EQ(u32.output, "[10]: 65538\n[12]: 196612\n");
    auto both = io("read --addr 40011-40014 --quantity 2");
    EXPECT_EQ(both.exit_code, 2) << both.output;
    EXPECT_THAT(both.output, HasSubstr("it says how many to read, without --quantity"));
    auto odd = io("read --addr 10-12 --type u32");
    EXPECT_EQ(odd.exit_code, 2) << odd.output;
    EXPECT_THAT(odd.output, HasSubstr("holds 3 registers, not a whole number of u32 values"));
}

TEST_F(ReadWrite, RefusalsNameTheFieldAndRange) {
    auto ro = io("write --addr 30001 5");
    EXPECT_EQ(ro.exit_code, 2) << ro.output;
    EXPECT_THAT(ro.output, HasSubstr("input_registers are read-only"));
    auto big = io("read --addr 0 --quantity 126");
    EXPECT_EQ(big.exit_code, 2) << big.output;
    EXPECT_THAT(big.output,
                HasSubstr("quantity 126: valid 1..125 for 0x03 read_holding_registers"));
    auto value = io("write --addr 0 70000");
    EXPECT_THAT(value.output, HasSubstr("value '70000': valid 0..65535 for u16"));
    auto table = io("read --table input_registers --addr 40001");
    EXPECT_THAT(table.output, HasSubstr("'40001' is a holding register reference"));
}

TEST(ReadWriteSafety, WritesToARemoteTargetNeedAllowWrites) {
    // Refused before connecting: 192.0.2.1 (TEST-NET-1) is never contacted.
    auto r = run_mbstorm("write --target 192.0.2.1 --addr 0 1", 30);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_THAT(r.output, HasSubstr("refusing to send write operations to 192.0.2.1"));
    EXPECT_THAT(r.output, HasSubstr("--allow-writes"));
}

TEST(ReadWriteHelp, StatesTheAddressRuleLikeEveryCommand) {
    for (const char* cmd : {"read --help", "write --help"}) {
        EXPECT_THAT(run_mbstorm(cmd).output,
                    HasSubstr("5-6 digits starting 0/1/3/4 are always reference"))
            << cmd;
    }
}

TEST(ReadWriteTarget, NoAnswerIsATimeoutWithExitOne) {
    std::unique_ptr<Target> server;
    const std::string target = start_reference_slave(server, {"--no-answer-rate", "100%"});
    ASSERT_FALSE(target.empty());
    auto r = run_mbstorm("read --target " + target + " --addr 0 --timeout 200ms --json", 30);
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_THAT(r.output, HasSubstr("\"error\":\"no answer within 200 ms\""));
}

TEST(ReadWriteTarget, UnreachableTargetIsOneLineExitTwo) {
    auto r = run_mbstorm("read --target 127.0.0.1:1 --addr 0", 30);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_THAT(r.output, HasSubstr("cannot connect to 127.0.0.1:1"));
}

}  // namespace
