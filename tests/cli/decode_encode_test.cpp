#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>

#include "../support/run_mbstorm.hpp"

using mbstorm::test::run_mbstorm;
using testing::HasSubstr;
using testing::Not;

TEST(DecodeCommand, RtuRequestShowsFieldsAndCorrectCrc) {
    auto r = run_mbstorm("decode 01 03 00 00 00 0A C5 CD");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_THAT(r.output, HasSubstr("Modbus RTU frame"));
    EXPECT_THAT(r.output, HasSubstr("read_holding_registers"));
    EXPECT_THAT(r.output, HasSubstr("Quantity of registers"));
    EXPECT_THAT(r.output, HasSubstr("correct"));
}

// 1 MB of hex used to be called "not a hex digit at character 8193" (issue #31).
TEST(DecodeCommand, TooManyBytesIsSaidSo) {
    std::string hex;
    for (int i = 0; i < 5000; ++i) hex += "AB";
    auto r = run_mbstorm("decode " + hex);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_THAT(r.output,
                HasSubstr("too many bytes: more than 4096 (the longest Modbus frame is 256)"));
    EXPECT_THAT(r.output, Not(HasSubstr("not a hex digit")));
}

TEST(DecodeCommand, RtuWrongCrcIsReported) {
    // Shown field by field, and the fault makes the exit code 1 (scripts can tell).
    auto r = run_mbstorm("decode --rtu 01 03 00 00 00 0A C5 CE");
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_THAT(r.output, HasSubstr("WRONG: expected C5 CD"));
    EXPECT_THAT(r.output, HasSubstr("Quantity of registers"));
}

TEST(DecodeCommand, AutoDetectionNamesTheMostPlausibleFramingAndItsFault) {
    // A read request in RTU framing with its CRC off by one: not "more bytes than needed".
    auto r = run_mbstorm("decode 11 03 00 6B 00 03 76 88");
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_THAT(r.output, HasSubstr("Modbus RTU frame (8 bytes, CRC BAD) request"));
    EXPECT_THAT(r.output, HasSubstr("read_holding_registers"));
    EXPECT_THAT(r.output,
                HasSubstr("mbstorm decode: read as Modbus RTU: CRC wrong: expected 76 87"));
    EXPECT_EQ(r.output.find("more bytes than"), std::string::npos) << r.output;
}

TEST(DecodeCommand, InvalidPduIsShownFieldByFieldWithTheBadFieldMarked) {
    auto r = run_mbstorm("decode --pdu --request 03 00 00 00 C8");
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_THAT(r.output, HasSubstr("Starting address"));
    EXPECT_THAT(r.output, HasSubstr("Quantity of registers  00 C8  200 (0x00C8)  <-- BAD: quantity "
                                    "200: valid 1..125 for 0x03 read_holding_registers"));
    // Auto-detection: the same bytes read as a bare PDU with the bad field named.
    auto guessed = run_mbstorm("decode 03 00 00 00 C8");
    EXPECT_EQ(guessed.exit_code, 1) << guessed.output;
    EXPECT_THAT(guessed.output, HasSubstr("read as a bare PDU: not a valid request: quantity 200"));
    auto coil = run_mbstorm("decode --pdu 05 00 01 12 34");
    EXPECT_THAT(coil.output, HasSubstr("<-- BAD: 0x1234: valid 0xFF00 (ON) or 0x0000 (OFF)"));
    auto tail = run_mbstorm("decode --pdu --request 03 00 00 00 01 FF");
    EXPECT_THAT(tail.output, HasSubstr("<-- BAD: 6 bytes: 0x03 read_holding_registers needs 5"));
    auto cut = run_mbstorm("decode --pdu --request 03 00 00");
    EXPECT_THAT(cut.output, HasSubstr("(end of bytes)"));
    EXPECT_THAT(cut.output, HasSubstr("3 bytes: 0x03 read_holding_registers needs 5"));
}

TEST(DecodeCommand, AsciiWrongLrcNamesTheExpectedOne) {
    auto r = run_mbstorm("decode :010300000001FC");
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_THAT(r.output, HasSubstr("WRONG: expected FB"));
    EXPECT_THAT(r.output, HasSubstr("LRC wrong: expected FB, the frame carries FC"));
}

TEST(DecodeCommand, TruncatedTcpFrameIsShownWithTheLengthMarked) {
    // Used to be read as a bare PDU with function code 0x00, then as one line and exit 2.
    auto r = run_mbstorm("decode 00 01 00 00 00 06 01 03 00 00");
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_THAT(r.output, HasSubstr("Modbus TCP ADU (10 bytes, cut short) request:"));
    EXPECT_THAT(r.output, HasSubstr("Transaction identifier"));
    EXPECT_THAT(r.output, HasSubstr("6 (unit id + PDU)  <-- BAD: the length field says 6 bytes "
                                    "follow it, 4 do"));
    EXPECT_THAT(r.output, HasSubstr("Starting address"));
    EXPECT_THAT(r.output, HasSubstr("3 bytes: 0x03 read_holding_registers needs 5"));
    EXPECT_THAT(r.output, HasSubstr("mbstorm decode: read as Modbus TCP: truncated Modbus TCP "
                                    "frame: the length field says 6 bytes follow it, 4 do"));
}

TEST(DecodeCommand, TcpLengthThatDisagreesIsNamed) {
    auto r = run_mbstorm("decode --tcp 00 01 00 00 00 09 01 03 00 00 00 0A");
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_THAT(r.output, HasSubstr("Quantity of registers"));
    EXPECT_THAT(r.output, HasSubstr("9 (unit id + PDU)  <-- BAD: the length field says 9 bytes "
                                    "follow it, 6 do"));
}

TEST(DecodeCommand, BytesLeftOverAfterATcpFrameAreShown) {
    auto r = run_mbstorm("decode --tcp 00 01 00 00 00 06 01 03 00 00 00 0A FF");
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_THAT(r.output, HasSubstr("Modbus TCP ADU #2 (1 byte, cut short):"));
    EXPECT_THAT(r.output, HasSubstr("FF     <-- BAD: 1 byte: an MBAP header needs 7"));
    EXPECT_THAT(r.output,
                HasSubstr("truncated Modbus TCP frame: 1 byte left over after 1 complete frame "
                          "(FF): 1 byte: an MBAP header needs 7"));
    EXPECT_THAT(r.output, Not(HasSubstr("1 bytes")));
    // Unnamed, sound frames with bytes after them are still TCP, not a bare PDU of function 0x00.
    auto guessed = run_mbstorm("decode 00 01 00 00 00 06 01 03 00 00 00 0A FF");
    EXPECT_EQ(guessed.exit_code, 1) << guessed.output;
    EXPECT_THAT(guessed.output,
                HasSubstr("read as Modbus TCP: truncated Modbus TCP frame: 1 byte"));
    // A second ADU cut short is shown as far as it goes, read as the request it can still be.
    auto second =
        run_mbstorm("decode --tcp 00 01 00 00 00 06 01 03 00 00 00 0A 00 02 00 00 00 06 01 03 00");
    EXPECT_EQ(second.exit_code, 1) << second.output;
    EXPECT_THAT(second.output, HasSubstr("Modbus TCP ADU #2 (9 bytes, cut short) request:"));
    EXPECT_THAT(second.output, HasSubstr("the length field says 6 bytes follow it, 3 do"));
    EXPECT_THAT(second.output, HasSubstr("9 bytes left over after 1 complete frame (00 02 00 00 "
                                         "00 06 01 03 00)"));
}

TEST(DecodeCommand, TruncatedRtuRequestIsShownCutShortNotAsAnotherFunction) {
    // As a bare PDU these bytes are a valid 0x11 response; as RTU, the read request of the
    // specification's example with its last three bytes missing.
    auto r = run_mbstorm("decode 11 03 00 6B 00");
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_THAT(r.output, HasSubstr("Modbus RTU frame (5 bytes, cut short) request:"));
    EXPECT_THAT(r.output, HasSubstr("Slave address"));
    EXPECT_THAT(r.output, HasSubstr("Starting address"));
    EXPECT_THAT(r.output, HasSubstr("<-- BAD: 0 of its 2 bytes there: 5 bytes: a 0x03 "
                                    "read_holding_registers request needs 8"));
    EXPECT_THAT(r.output, HasSubstr("mbstorm decode: read as Modbus RTU: truncated: 5 bytes: a "
                                    "0x03 read_holding_registers request needs 8"));
    // The other reading is named, not shown: the user chooses with --pdu.
    EXPECT_THAT(r.output, HasSubstr("the same bytes are also a sound Modbus PDU (5 bytes) "
                                    "response: --pdu shows it"));
    EXPECT_THAT(r.output, Not(HasSubstr("Function code     11")));
    // Told it is RTU, a frame of three bytes is shown as far as it goes too.
    auto cut = run_mbstorm("decode --rtu --request 01 03 00");
    EXPECT_EQ(cut.exit_code, 1) << cut.output;
    EXPECT_THAT(cut.output, HasSubstr("3 bytes: a 0x03 read_holding_registers request needs 8"));
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
    for (const char* args :
         {"decode ZZ", "decode 0", "decode --tcp 00 01 00 00 00 00 01", "decode --rtu 01"}) {
        auto r = run_mbstorm(args);
        EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.output;
        EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << args << "\n"
                                                                         << r.output;
    }
}

TEST(DecodeCommand, NonModbusProtocolIdIsShownAndFlagged) {
    auto r = run_mbstorm("decode --tcp 00 01 00 05 00 06 01 03 00 00 00 0A");
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_THAT(r.output, HasSubstr("not Modbus"));
    EXPECT_THAT(r.output, HasSubstr("protocol identifier 5 (0x0005): Modbus is 0"));
}

TEST(EncodeCommand, BuildsFramesInEveryFraming) {
    EXPECT_EQ(run_mbstorm("encode --fc 3 --addr 0 --quantity 10 --rtu").output,
              "01 03 00 00 00 0A C5 CD\n");
    EXPECT_EQ(run_mbstorm("encode --fc read_holding_registers --quantity 10 --tid 1").output,
              "00 01 00 00 00 06 01 03 00 00 00 0A\n");
    EXPECT_EQ(run_mbstorm("encode --fc 3 --quantity 1 --ascii").output, ":010300000001FB\n");
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
    auto r = run_mbstorm("encode --fc 3 --quantity 126");
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_THAT(r.output, HasSubstr("quantity"));
    EXPECT_EQ(run_mbstorm("encode --fc nonsense").exit_code, 2);
}

// Every refusal names the field, the value and the valid range, in one line.
TEST(EncodeCommand, RefusalsNameFieldValueAndRange) {
    const std::pair<const char*, const char*> cases[] = {
        {"encode --fc 3 --quantity 200",
         "quantity 200: valid 1..125 for 0x03 read_holding_registers"},
        {"encode --fc 99",
         "function code 99 (0x63): not a public Modbus function; valid: 0x01 0x02 0x03 0x04 "
         "0x05 0x06 0x07 0x08 0x0B"},
        {"encode --fc nonsense", "function 'nonsense' is not a function code; write a name"},
        {"encode --fc 1 --quantity 0", "quantity 0: valid 1..2000 for 0x01 read_coils"},
        {"encode --fc 3 --addr 0xFFFF --quantity 2", "address 65535 + quantity 2 runs past 65535"},
        {"encode --fc 16 --addr 0", "--values holds 0 value(s): valid 1..123 for 0x10"},
        {"encode --fc 5 --value 7", "--value 7 for 0x05 write_single_coil: valid 0 (OFF) or 1"},
        {"encode --fc 8 --sub 19", "sub-function 0x0013: valid 0x0000..0x0004"},
        {"encode --fc 0x17 --quantity 126 --values 1", "quantity 126: valid 1..125 for 0x17"},
        {"encode --fc 20 --quantity 200",
         "--quantity 200 (record length): valid 1..121 for 0x14 read_file_record"},
        {"encode --fc 21 --values 1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17,18,19,20,21,22,23,24,"
         "25,26,27,28,29,30,31,32,33,34,35,36,37,38,39,40,41,42,43,44,45,46,47,48,49,50,51,52,53,"
         "54,55,56,57,58,59,60,61,62,63,64,65,66,67,68,69,70,71,72,73,74,75,76,77,78,79,80,81,82,"
         "83,84,85,86,87,88,89,90,91,92,93,94,95,96,97,98,99,100,101,102,103,104,105,106,107,108,"
         "109,110,111,112,113,114,115,116,117,118,119,120,121,122,123",
         "--values holds 123 value(s): valid 1..122 for 0x15 write_file_record"},
        {"encode --fc 20 --record 9999 --quantity 2", "--record 9999 + record length 2 runs past"},
    };
    for (const auto& [args, message] : cases) {
        auto r = run_mbstorm(args);
        EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.output;
        EXPECT_THAT(r.output, HasSubstr(message)) << args;
        EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << args << "\n"
                                                                         << r.output;
    }
}

TEST(Cli, UnknownSubcommandIsUsageError) {
    EXPECT_EQ(run_mbstorm("frobnicate").exit_code, 2);
}
