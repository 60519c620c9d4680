// Exception codes and their precedence (spec state diagrams: 01, then 03, then 02, then 04),
// and table-size limits.
#include <gtest/gtest.h>

#include "slave_test_support.hpp"

namespace mbstorm::slave::test {
namespace {

using codec::ExceptionCode;

TEST(HandlerExceptions, UnsupportedFunctionsAnswer01WithTheExceptionBit) {
    DataModel m(small_config());
    for (unsigned fc : {0x00u, 0x09u, 0x0Au, 0x0Du, 0x0Eu, 0x12u, 0x13u, 0x19u, 0x28u, 0x2Au, 0x2Cu,
                        0x41u, 0x64u, 0x7Fu}) {
        const Reply r = call(m, Pdu(static_cast<std::uint8_t>(fc)).u16(0).u16(1));
        ASSERT_TRUE(r.is_exception(ExceptionCode::IllegalFunction)) << fc;
        EXPECT_EQ(r.bytes[0], fc | 0x80) << fc;
        EXPECT_EQ(r.result.function, fc);
    }
}

TEST(HandlerExceptions, FunctionBytesWithTheHighBitSetAre01Too) {
    DataModel m(small_config());
    for (unsigned fc : {0x80u, 0x83u, 0xABu, 0xFFu}) {
        const Reply r = call(m, Pdu(static_cast<std::uint8_t>(fc)).u16(0).u16(1));
        ASSERT_TRUE(r.is_exception(ExceptionCode::IllegalFunction)) << fc;
        EXPECT_EQ(r.bytes[0], fc);
    }
}

TEST(HandlerExceptions, UnsupportedFunctionOutranksMalformedData) {
    DataModel m(small_config());
    EXPECT_TRUE(call(m, Pdu(0x09)).is_exception(ExceptionCode::IllegalFunction));
    EXPECT_TRUE(call(m, Pdu(0x41).u8(1)).is_exception(ExceptionCode::IllegalFunction));
}

TEST(HandlerExceptions, ReadQuantityOutOfRangeIs03) {
    DataModel m(small_config());
    for (std::uint8_t fc : {0x03, 0x04}) {
        EXPECT_TRUE(call(m, Pdu(fc).u16(0).u16(0)).is_exception(ExceptionCode::IllegalDataValue));
        EXPECT_TRUE(call(m, Pdu(fc).u16(0).u16(126)).is_exception(ExceptionCode::IllegalDataValue));
    }
    for (std::uint8_t fc : {0x01, 0x02}) {
        EXPECT_TRUE(call(m, Pdu(fc).u16(0).u16(0)).is_exception(ExceptionCode::IllegalDataValue));
        EXPECT_TRUE(
            call(m, Pdu(fc).u16(0).u16(2001)).is_exception(ExceptionCode::IllegalDataValue));
    }
}

TEST(HandlerExceptions, BadQuantityAndBadAddressTogetherGive03) {
    DataModel m(small_config(100));
    // Outside the table (02) and quantity out of range (03): 03 wins.
    EXPECT_TRUE(call(m, Pdu(0x03).u16(5000).u16(0)).is_exception(ExceptionCode::IllegalDataValue));
    EXPECT_TRUE(
        call(m, Pdu(0x03).u16(0xFFFF).u16(126)).is_exception(ExceptionCode::IllegalDataValue));
    EXPECT_TRUE(
        call(m, Pdu(0x01).u16(0xFFF0).u16(2001)).is_exception(ExceptionCode::IllegalDataValue));
    // FC0F/10: byte count mismatch with an address outside the table.
    EXPECT_TRUE(call(m, Pdu(0x0F).u16(5000).u16(9).u8(1).u8(0xFF))
                    .is_exception(ExceptionCode::IllegalDataValue));
    EXPECT_TRUE(call(m, Pdu(0x10).u16(5000).u16(2).u8(2).u16(1))
                    .is_exception(ExceptionCode::IllegalDataValue));
    EXPECT_TRUE(call(m, Pdu(0x10).u16(5000).u16(124).u8(248))
                    .is_exception(ExceptionCode::IllegalDataValue));
}

TEST(HandlerExceptions, AddressPastTheTableIs02) {
    DataModel m(small_config(100));
    EXPECT_EQ(call(m, Pdu(0x03).u16(99).u16(1)).result.outcome, Outcome::Response);
    EXPECT_TRUE(call(m, Pdu(0x03).u16(99).u16(2)).is_exception(ExceptionCode::IllegalDataAddress));
    EXPECT_TRUE(call(m, Pdu(0x03).u16(100).u16(1)).is_exception(ExceptionCode::IllegalDataAddress));
    EXPECT_TRUE(call(m, Pdu(0x04).u16(100).u16(1)).is_exception(ExceptionCode::IllegalDataAddress));
    EXPECT_TRUE(call(m, Pdu(0x01).u16(93).u16(8)).is_exception(ExceptionCode::IllegalDataAddress));
    EXPECT_TRUE(call(m, Pdu(0x02).u16(100).u16(1)).is_exception(ExceptionCode::IllegalDataAddress));
    EXPECT_TRUE(
        call(m, Pdu(0x05).u16(100).u16(0xFF00)).is_exception(ExceptionCode::IllegalDataAddress));
    EXPECT_TRUE(call(m, Pdu(0x06).u16(100).u16(1)).is_exception(ExceptionCode::IllegalDataAddress));
    EXPECT_TRUE(call(m, Pdu(0x0F).u16(95).u16(8).u8(1).u8(0xFF))
                    .is_exception(ExceptionCode::IllegalDataAddress));
    EXPECT_TRUE(call(m, Pdu(0x10).u16(99).u16(2).u8(4).words({1, 2}))
                    .is_exception(ExceptionCode::IllegalDataAddress));
    // Nothing was written by the refused requests.
    EXPECT_FALSE(m.coils().get(95));
    EXPECT_EQ(m.holding_registers().get(99), 0);
}

TEST(HandlerExceptions, RangeWrappingPast0xFFFFIs02) {
    DataModel m;  // full tables: only the 16-bit wrap can fail
    EXPECT_TRUE(
        call(m, Pdu(0x03).u16(0xFFFF).u16(2)).is_exception(ExceptionCode::IllegalDataAddress));
    EXPECT_EQ(call(m, Pdu(0x03).u16(0xFFFF).u16(1)).result.outcome, Outcome::Response);
    EXPECT_TRUE(
        call(m, Pdu(0x01).u16(0xFFFF).u16(2)).is_exception(ExceptionCode::IllegalDataAddress));
}

TEST(HandlerExceptions, WriteQuantityLimitsAre03) {
    DataModel m;
    EXPECT_TRUE(
        call(m, Pdu(0x0F).u16(0).u16(0).u8(0)).is_exception(ExceptionCode::IllegalDataValue));
    Pdu coils(0x0F);
    coils.u16(0).u16(1969).u8(247);
    for (int i = 0; i < 247; ++i) coils.u8(0);
    EXPECT_TRUE(call(m, coils).is_exception(ExceptionCode::IllegalDataValue));
    EXPECT_TRUE(
        call(m, Pdu(0x10).u16(0).u16(0).u8(0)).is_exception(ExceptionCode::IllegalDataValue));
}

TEST(HandlerExceptions, TruncatedAndOverlongPdusAre03) {
    DataModel m(small_config());
    EXPECT_TRUE(call(m, Pdu(0x03).u16(0)).is_exception(ExceptionCode::IllegalDataValue));
    EXPECT_TRUE(
        call(m, Pdu(0x03).u16(0).u16(1).u8(0)).is_exception(ExceptionCode::IllegalDataValue));
    EXPECT_TRUE(call(m, Pdu(0x06).u16(0)).is_exception(ExceptionCode::IllegalDataValue));
    EXPECT_TRUE(call(m, Pdu(0x10).u16(0).u16(2).u8(4).u16(1))
                    .is_exception(ExceptionCode::IllegalDataValue));
    EXPECT_TRUE(call(m, Pdu(0x16).u16(0).u16(0)).is_exception(ExceptionCode::IllegalDataValue));
}

TEST(HandlerExceptions, EmptyPduOrSmallBufferGetsNoResponse) {
    DataModel m(small_config());
    std::uint8_t out[kMinOutput];
    EXPECT_EQ(handle_request(codec::Bytes{}, m, out).outcome, Outcome::NoResponse);
    const std::vector<std::uint8_t> req = Pdu(0x03).u16(0).u16(1);
    std::uint8_t small[100];
    EXPECT_EQ(handle_request(req, m, small).outcome, Outcome::NoResponse);
}

TEST(HandlerExceptions, ExceptionResponsesDecodeAsExceptions) {
    DataModel m(small_config());
    const Reply r = call(m, Pdu(0x03).u16(100).u16(1));
    ASSERT_EQ(r.decode_error, codec::CodecError::Ok);
    EXPECT_EQ(r.decoded.function, 0x03);
    EXPECT_EQ(r.decoded.exception, ExceptionCode::IllegalDataAddress);
}

TEST(HandlerTableSizes, ZeroSizedTableRefusesEveryAddress) {
    ModelConfig c;
    c.sizes = {0, 10, 0, 10};
    DataModel m(c);
    EXPECT_TRUE(call(m, Pdu(0x01).u16(0).u16(1)).is_exception(ExceptionCode::IllegalDataAddress));
    EXPECT_TRUE(call(m, Pdu(0x04).u16(0).u16(1)).is_exception(ExceptionCode::IllegalDataAddress));
    EXPECT_EQ(call(m, Pdu(0x02).u16(0).u16(10)).result.outcome, Outcome::Response);
    EXPECT_EQ(call(m, Pdu(0x03).u16(0).u16(10)).result.outcome, Outcome::Response);
}

TEST(HandlerTableSizes, EachTableHasItsOwnLimit) {
    ModelConfig c;
    c.sizes = {16, 32, 64, 128};
    DataModel m(c);
    EXPECT_EQ(call(m, Pdu(0x01).u16(15).u16(1)).result.outcome, Outcome::Response);
    EXPECT_TRUE(call(m, Pdu(0x01).u16(16).u16(1)).is_exception(ExceptionCode::IllegalDataAddress));
    EXPECT_EQ(call(m, Pdu(0x02).u16(31).u16(1)).result.outcome, Outcome::Response);
    EXPECT_TRUE(call(m, Pdu(0x02).u16(32).u16(1)).is_exception(ExceptionCode::IllegalDataAddress));
    EXPECT_EQ(call(m, Pdu(0x04).u16(63).u16(1)).result.outcome, Outcome::Response);
    EXPECT_TRUE(call(m, Pdu(0x04).u16(64).u16(1)).is_exception(ExceptionCode::IllegalDataAddress));
    EXPECT_EQ(call(m, Pdu(0x03).u16(3).u16(125)).result.outcome, Outcome::Response);
    EXPECT_TRUE(call(m, Pdu(0x03).u16(4).u16(125)).is_exception(ExceptionCode::IllegalDataAddress));
    EXPECT_EQ(m.table_size(Table::HoldingRegisters), 128u);
}

TEST(HandlerTableSizes, AboveFullSizeIsRejectedAtConstruction) {
    ModelConfig c;
    c.sizes.coils = 65537;
    EXPECT_THROW(DataModel{c}, std::invalid_argument);
}

}  // namespace
}  // namespace mbstorm::slave::test
