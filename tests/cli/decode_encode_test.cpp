#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>

#include "../support/run_mbstorm.hpp"

using mbstorm::test::run_mbstorm;
using testing::HasSubstr;

TEST(DecodeCommand, RtuRequestShowsFieldsAndCorrectCrc) {
    auto r = run_mbstorm("decode 01 03 00 00 00 0A C5 CD");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_THAT(r.output, HasSubstr("Modbus RTU frame"));
    EXPECT_THAT(r.output, HasSubstr("read_holding_registers"));
    EXPECT_THAT(r.output, HasSubstr("Quantity of registers"));
    EXPECT_THAT(r.output, HasSubstr("correct"));
}

TEST(DecodeCommand, RtuWrongCrcIsReported) {
    auto r = run_mbstorm("decode --rtu 01 03 00 00 00 0A C5 CE");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_THAT(r.output, HasSubstr("WRONG: expected C5 CD"));
}

TEST(DecodeCommand, HexWithoutSpacesAndTcpDetected) {
    auto r = run_mbstorm("decode 000100000006010300000001");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_THAT(r.output, HasSubstr("Transaction identifier"));
    EXPECT_THAT(r.output, HasSubstr("Unit identifier"));
}

TEST(DecodeCommand, ExceptionResponseIsNamed) {
    auto r = run_mbstorm("decode 01 83 02 C0 F1");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_THAT(r.output, HasSubstr("ILLEGAL DATA ADDRESS"));
}

TEST(DecodeCommand, AmbiguousRtuFrameShowsBothDirectionsUnlessTold) {
    // FC06's response echoes its request, so both readings fit.
    auto both = run_mbstorm("decode 01 06 00 01 00 03 98 0B");
    EXPECT_EQ(both.exit_code, 0) << both.output;
    EXPECT_THAT(both.output, HasSubstr("request:"));
    EXPECT_THAT(both.output, HasSubstr("response:"));
    auto only = run_mbstorm("decode --response 01 06 00 01 00 03 98 0B");
    EXPECT_EQ(only.output.find("request:"), std::string::npos) << only.output;
}

TEST(DecodeCommand, AsciiFrame) {
    auto r = run_mbstorm("decode :010300000001FB");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_THAT(r.output, HasSubstr("LRC"));
}

TEST(DecodeCommand, PipelinedTcpFramesAreAllShown) {
    auto r = run_mbstorm(
        "decode --tcp --request 00 01 00 00 00 06 01 03 00 00 00 0A 00 02 00 00 00 06 01 04 00 10 "
        "00 02");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_THAT(r.output, HasSubstr("#1"));
    EXPECT_THAT(r.output, HasSubstr("#2"));
    EXPECT_THAT(r.output, HasSubstr("read_input_registers"));
}

TEST(DecodeCommand, BadInputIsOneLineAndExitTwo) {
    for (const char* args : {"decode ZZ", "decode 0", "decode --tcp 00 01 00 00 00 00 01",
                             "decode --rtu 01 03 00", "decode --pdu --request 03 00 00 00 00"}) {
        auto r = run_mbstorm(args);
        EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.output;
        EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << args << "\n"
                                                                         << r.output;
    }
}

TEST(DecodeCommand, NonModbusProtocolIdIsShownAndFlagged) {
    auto r = run_mbstorm("decode --tcp 00 01 00 05 00 06 01 03 00 00 00 0A");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_THAT(r.output, HasSubstr("not Modbus"));
}

TEST(EncodeCommand, BuildsFramesInEveryFraming) {
    EXPECT_EQ(run_mbstorm("encode --fc 3 --addr 0 --count 10 --rtu").output,
              "01 03 00 00 00 0A C5 CD\n");
    EXPECT_EQ(run_mbstorm("encode --fc read_holding_registers --count 10 --tid 1").output,
              "00 01 00 00 00 06 01 03 00 00 00 0A\n");
    EXPECT_EQ(run_mbstorm("encode --fc 3 --count 1 --ascii").output, ":010300000001FB\n");
    // Reference 40100 is holding register 99 (0x63).
    EXPECT_EQ(run_mbstorm("encode --ref 40100 --pdu").output, "03 00 63 00 01\n");
}

TEST(EncodeCommand, WriteMultipleRegistersAndCoils) {
    EXPECT_EQ(run_mbstorm("encode --fc 16 --addr 1 --values 10,258 --pdu").output,
              "10 00 01 00 02 04 00 0A 01 02\n");
    EXPECT_EQ(run_mbstorm("encode --fc 15 --addr 19 --values 1,0,1,1,0,0,1,1,1,0 --pdu").output,
              "0F 00 13 00 0A 02 CD 01\n");
}

TEST(EncodeCommand, OutOfSpecFieldsAreRejected) {
    auto r = run_mbstorm("encode --fc 3 --count 126");
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_THAT(r.output, HasSubstr("quantity"));
    EXPECT_EQ(run_mbstorm("encode --fc nonsense").exit_code, 2);
}

TEST(Cli, UnknownSubcommandIsUsageError) {
    EXPECT_EQ(run_mbstorm("frobnicate").exit_code, 2);
}
