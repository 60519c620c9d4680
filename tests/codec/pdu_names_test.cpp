// Function, exception and error names.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "codec/error.hpp"
#include "codec/exception_code.hpp"
#include "codec/function_code.hpp"
#include "codec/limits.hpp"

namespace mbstorm::codec {
namespace {

TEST(FunctionNames, EverySupportedCodeRoundTripsThroughItsName) {
    int supported = 0;
    std::set<std::string_view> names;
    for (int fc = 0; fc < 256; ++fc) {
        const auto b = static_cast<std::uint8_t>(fc);
        const std::string_view name = function_name(b);
        EXPECT_EQ(is_supported_function(b), !name.empty());
        if (name.empty()) continue;
        ++supported;
        names.insert(name);
        std::uint8_t back = 0;
        ASSERT_TRUE(function_from_name(name, back)) << name;
        EXPECT_EQ(back, b);
    }
    EXPECT_EQ(supported, 19);
    EXPECT_EQ(names.size(), 19u);
    EXPECT_EQ(function_name(0x03), "read_holding_registers");
    EXPECT_EQ(function_name(0x17), "read_write_multiple_registers");
    std::uint8_t fc = 0;
    EXPECT_FALSE(function_from_name("read_everything", fc));
    EXPECT_FALSE(function_from_name("", fc));
}

TEST(FunctionNames, WriteFunctions) {
    std::set<int> writes;
    for (int fc = 0; fc < 256; ++fc) {
        if (is_write_function(static_cast<std::uint8_t>(fc))) writes.insert(fc);
    }
    EXPECT_EQ(writes, (std::set<int>{0x05, 0x06, 0x08, 0x0F, 0x10, 0x15, 0x16, 0x17}));
}

TEST(ExceptionNames, SpecNames) {
    EXPECT_EQ(exception_name(ExceptionCode::IllegalFunction), "ILLEGAL FUNCTION");
    EXPECT_EQ(exception_name(ExceptionCode::IllegalDataAddress), "ILLEGAL DATA ADDRESS");
    EXPECT_EQ(exception_name(ExceptionCode::IllegalDataValue), "ILLEGAL DATA VALUE");
    EXPECT_EQ(exception_name(ExceptionCode::ServerDeviceFailure), "SERVER DEVICE FAILURE");
    EXPECT_EQ(exception_name(ExceptionCode::Acknowledge), "ACKNOWLEDGE");
    EXPECT_EQ(exception_name(ExceptionCode::ServerDeviceBusy), "SERVER DEVICE BUSY");
    EXPECT_EQ(exception_name(ExceptionCode::MemoryParityError), "MEMORY PARITY ERROR");
    EXPECT_EQ(exception_name(ExceptionCode::GatewayPathUnavailable), "GATEWAY PATH UNAVAILABLE");
    EXPECT_EQ(exception_name(ExceptionCode::GatewayTargetFailedToRespond),
              "GATEWAY TARGET DEVICE FAILED TO RESPOND");
    EXPECT_EQ(exception_name(static_cast<ExceptionCode>(0x07)), "UNKNOWN EXCEPTION");
    EXPECT_EQ(exception_name(ExceptionCode::None), "UNKNOWN EXCEPTION");
    int known = 0;
    for (int c = 0; c < 256; ++c) known += is_known_exception(static_cast<std::uint8_t>(c));
    EXPECT_EQ(known, 9);
}

TEST(ErrorNames, EveryErrorHasADistinctNameAndDescription) {
    std::set<std::string_view> names;
    for (int e = 0; e <= static_cast<int>(CodecError::FrameTooLong); ++e) {
        const auto err = static_cast<CodecError>(e);
        EXPECT_NE(error_name(err), "unknown_error") << e;
        EXPECT_FALSE(error_description(err).empty());
        names.insert(error_name(err));
    }
    EXPECT_EQ(names.size(), static_cast<std::size_t>(CodecError::FrameTooLong) + 1);
    EXPECT_EQ(error_name(CodecError::Truncated), "truncated");
}

// Seed 000 claims a TCP ADU is "249 + 7 = 256 bytes"; spec v1.1b3 (4.1) says a PDU is at most
// 253 bytes, so a TCP ADU is 253 + 7 = 260. The spec wins.
TEST(Limits, PduAndAduSizesFollowTheSpec) {
    EXPECT_EQ(limits::kMaxPdu, 253u);
    EXPECT_EQ(limits::kMaxTcpAdu, 260u);
    EXPECT_EQ(limits::kMaxRtuAdu, 256u);
    // Seed 002 gives FC15/16 quantity "0x0000 TO 0x7B0" for both; the spec says FC0F 1..0x7B0
    // and FC10 1..0x7B. Seed 000 says FC04 reads "1~2000" registers; the spec says 1..125.
    EXPECT_EQ(limits::kMaxWriteCoils, 0x7B0);
    EXPECT_EQ(limits::kMaxWriteRegisters, 0x7B);
    EXPECT_EQ(limits::kMaxReadRegisters, 0x7D);
}

}  // namespace
}  // namespace mbstorm::codec
