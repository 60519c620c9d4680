// Reads and writes of the four tables: FC01-06, 0F, 10, 16, 17.
#include <gtest/gtest.h>

#include "slave_test_support.hpp"

namespace mbstorm::slave::test {
namespace {

using codec::CodecError;
using codec::ExceptionCode;

TEST(HandlerRead, HoldingRegistersComeBackBigEndian) {
    DataModel m(small_config());
    for (unsigned i = 0; i < 10; ++i)
        m.holding_registers().set(static_cast<std::uint16_t>(5 + i),
                                  static_cast<std::uint16_t>(0x1200 + i));
    const Reply r = call(m, Pdu(0x03).u16(5).u16(10));
    ASSERT_EQ(r.result.outcome, Outcome::Response);
    ASSERT_EQ(r.bytes.size(), 22u);
    EXPECT_EQ(r.bytes[0], 0x03);
    EXPECT_EQ(r.bytes[1], 20);
    for (unsigned i = 0; i < 10; ++i) EXPECT_EQ(r.reg(i), 0x1200 + i);
    EXPECT_EQ(r.decode_error, CodecError::Ok);
    EXPECT_FALSE(r.result.wrote);
}

TEST(HandlerRead, InputRegistersAreASeparateTable) {
    DataModel m(small_config());
    m.input_registers().set(0, 0xBEEF);
    m.holding_registers().set(0, 0x1111);
    const Reply r = call(m, Pdu(0x04).u16(0).u16(1));
    ASSERT_EQ(r.bytes.size(), 4u);
    EXPECT_EQ(r.reg(0), 0xBEEF);
}

TEST(HandlerRead, CoilsPackLsbFirstWithZeroPadding) {
    DataModel m(small_config());
    // Spec example: coils 20..38 = CD 6B 05
    const std::uint8_t packed[] = {0xCD, 0x6B, 0x05};
    m.coils().write_packed(20, 19, packed);
    m.coils().set(39, true);  // just past the requested range: must not leak into the padding
    const Reply r = call(m, Pdu(0x01).u16(20).u16(19));
    ASSERT_EQ(r.bytes, (std::vector<std::uint8_t>{0x01, 0x03, 0xCD, 0x6B, 0x05}));
    EXPECT_EQ(r.decode_error, CodecError::Ok);
}

TEST(HandlerRead, DiscreteInputsAreASeparateTable) {
    DataModel m(small_config());
    m.discrete_inputs().set(1, true);
    m.coils().set(0, true);
    const Reply r = call(m, Pdu(0x02).u16(0).u16(8));
    ASSERT_EQ(r.bytes, (std::vector<std::uint8_t>{0x02, 0x01, 0x02}));
}

TEST(HandlerRead, MaximumQuantitiesAreServed) {
    DataModel m;  // full 65536-entry tables
    EXPECT_EQ(call(m, Pdu(0x01).u16(0).u16(2000)).bytes.size(), 2u + 250u);
    EXPECT_EQ(call(m, Pdu(0x03).u16(65536 - 125).u16(125)).bytes.size(), 2u + 250u);
}

TEST(HandlerWrite, SingleCoilOnAndOff) {
    DataModel m(small_config());
    const auto on = Pdu(0x05).u16(7).u16(0xFF00);
    Reply r = call(m, on);
    EXPECT_EQ(r.bytes, on.bytes());  // echo
    EXPECT_TRUE(r.result.wrote);
    EXPECT_TRUE(m.coils().get(7));
    r = call(m, Pdu(0x05).u16(7).u16(0x0000));
    EXPECT_FALSE(m.coils().get(7));
}

TEST(HandlerWrite, SingleCoilRejectsOtherValuesWith03) {
    DataModel m(small_config());
    EXPECT_TRUE(
        call(m, Pdu(0x05).u16(7).u16(0x0001)).is_exception(ExceptionCode::IllegalDataValue));
    EXPECT_TRUE(
        call(m, Pdu(0x05).u16(7).u16(0xFFFF)).is_exception(ExceptionCode::IllegalDataValue));
    // Bad value outranks a bad address (03 before 02).
    EXPECT_TRUE(
        call(m, Pdu(0x05).u16(5000).u16(0x1234)).is_exception(ExceptionCode::IllegalDataValue));
    EXPECT_FALSE(m.coils().get(7));
}

TEST(HandlerWrite, SingleRegisterEchoes) {
    DataModel m(small_config());
    const auto req = Pdu(0x06).u16(99).u16(0xCAFE);
    EXPECT_EQ(call(m, req).bytes, req.bytes());
    EXPECT_EQ(m.holding_registers().get(99), 0xCAFE);
}

TEST(HandlerWrite, MultipleCoilsIgnoreThePaddingBits) {
    DataModel m(small_config());
    // 10 coils from 20: CD 01 -> 1011 0011 10 ; the padding bits of 0xFF must be ignored.
    const Reply r = call(m, Pdu(0x0F).u16(20).u16(10).u8(2).u8(0xCD).u8(0xFD));
    ASSERT_EQ(r.bytes, (std::vector<std::uint8_t>{0x0F, 0x00, 20, 0x00, 10}));
    const bool expected[10] = {1, 0, 1, 1, 0, 0, 1, 1, 1, 0};
    for (unsigned i = 0; i < 10; ++i)
        EXPECT_EQ(m.coils().get(static_cast<std::uint16_t>(20 + i)), expected[i]) << i;
    EXPECT_FALSE(m.coils().get(30));
}

TEST(HandlerWrite, MultipleRegisters) {
    DataModel m(small_config());
    const Reply r = call(m, Pdu(0x10).u16(1).u16(2).u8(4).words({0x000A, 0x0102}));
    ASSERT_EQ(r.bytes, (std::vector<std::uint8_t>{0x10, 0x00, 0x01, 0x00, 0x02}));
    EXPECT_EQ(m.holding_registers().get(1), 0x000A);
    EXPECT_EQ(m.holding_registers().get(2), 0x0102);
    EXPECT_TRUE(r.result.wrote);
}

// Spec example: current 0x12, AND 0xF2, OR 0x25 -> 0x17.
TEST(HandlerMaskWrite, SpecExample) {
    DataModel m(small_config());
    m.holding_registers().set(4, 0x0012);
    const auto req = Pdu(0x16).u16(4).u16(0x00F2).u16(0x0025);
    EXPECT_EQ(call(m, req).bytes, req.bytes());
    EXPECT_EQ(m.holding_registers().get(4), 0x0017);
}

TEST(HandlerMaskWrite, FormulaHoldsForEveryMaskCombination) {
    DataModel m(small_config());
    const std::uint16_t currents[] = {0x0000, 0xFFFF, 0xA5A5, 0x1234};
    const std::uint16_t masks[] = {0x0000, 0xFFFF, 0x0F0F, 0xF00F, 0x8001};
    for (auto cur : currents)
        for (auto a : masks)
            for (auto o : masks) {
                m.holding_registers().set(0, cur);
                call(m, Pdu(0x16).u16(0).u16(a).u16(o));
                const auto want = static_cast<std::uint16_t>((cur & a) | (o & ~a));
                EXPECT_EQ(m.holding_registers().get(0), want) << cur << " " << a << " " << o;
            }
    // AND 0xFFFF, OR 0: no change; AND 0: the register becomes the OR mask.
    m.holding_registers().set(0, 0x4321);
    call(m, Pdu(0x16).u16(0).u16(0xFFFF).u16(0x0000));
    EXPECT_EQ(m.holding_registers().get(0), 0x4321);
    call(m, Pdu(0x16).u16(0).u16(0x0000).u16(0x00FF));
    EXPECT_EQ(m.holding_registers().get(0), 0x00FF);
}

TEST(HandlerMaskWrite, AddressOutsideTableIs02) {
    DataModel m(small_config(10));
    EXPECT_TRUE(
        call(m, Pdu(0x16).u16(10).u16(0).u16(0)).is_exception(ExceptionCode::IllegalDataAddress));
}

TEST(HandlerReadWrite, WriteHappensBeforeRead) {
    DataModel m(small_config());
    for (unsigned i = 0; i < 10; ++i)
        m.holding_registers().set(static_cast<std::uint16_t>(i),
                                  static_cast<std::uint16_t>(100 + i));
    // Read 0..5, write 3..4: the read must show the new values at 3 and 4.
    const Reply r = call(m, Pdu(0x17).u16(0).u16(6).u16(3).u16(2).u8(4).words({0xAAAA, 0xBBBB}));
    ASSERT_EQ(r.result.outcome, Outcome::Response);
    ASSERT_EQ(r.bytes.size(), 2u + 12u);
    EXPECT_EQ(r.bytes[1], 12);
    EXPECT_EQ(r.reg(0), 100);
    EXPECT_EQ(r.reg(2), 102);
    EXPECT_EQ(r.reg(3), 0xAAAA);
    EXPECT_EQ(r.reg(4), 0xBBBB);
    EXPECT_EQ(r.reg(5), 105);
    EXPECT_TRUE(r.result.wrote);
    EXPECT_EQ(r.decode_error, CodecError::Ok);
}

TEST(HandlerReadWrite, EitherRangeOutsideTheTableIs02AndNothingIsWritten) {
    DataModel m(small_config(20));
    EXPECT_TRUE(call(m, Pdu(0x17).u16(15).u16(6).u16(0).u16(1).u8(2).words({7}))
                    .is_exception(ExceptionCode::IllegalDataAddress));
    EXPECT_EQ(m.holding_registers().get(0), 0);
    EXPECT_TRUE(call(m, Pdu(0x17).u16(0).u16(1).u16(19).u16(2).u8(4).words({7, 8}))
                    .is_exception(ExceptionCode::IllegalDataAddress));
    EXPECT_EQ(m.holding_registers().get(19), 0);
}

TEST(HandlerReadWrite, QuantityLimits) {
    DataModel m;
    // Read part 1..125, write part 1..121.
    EXPECT_TRUE(call(m, Pdu(0x17).u16(0).u16(126).u16(0).u16(1).u8(2).words({1}))
                    .is_exception(ExceptionCode::IllegalDataValue));
    EXPECT_TRUE(call(m, Pdu(0x17).u16(0).u16(0).u16(0).u16(1).u8(2).words({1}))
                    .is_exception(ExceptionCode::IllegalDataValue));
    Pdu big(0x17);
    big.u16(0).u16(125).u16(0).u16(122).u8(244);
    for (int i = 0; i < 122; ++i) big.u16(1);
    EXPECT_TRUE(call(m, big).is_exception(ExceptionCode::IllegalDataValue));
}

TEST(HandlerExceptionStatus, ReturnsConfiguredByte) {
    ModelConfig c = small_config();
    c.exception_status = 0x6D;
    DataModel m(c);
    EXPECT_EQ(call(m, Pdu(0x07)).bytes, (std::vector<std::uint8_t>{0x07, 0x6D}));
    m.set_exception_status(0x01);
    EXPECT_EQ(call(m, Pdu(0x07)).bytes, (std::vector<std::uint8_t>{0x07, 0x01}));
    EXPECT_TRUE(call(m, Pdu(0x07).u8(0)).is_exception(ExceptionCode::IllegalDataValue));
}

TEST(HandlerServerId, IdBytesThenRunIndicator) {
    ModelConfig c = small_config();
    c.server_id = {0x42, 0x43};
    c.run_indicator_on = true;
    DataModel m(c);
    const Reply r = call(m, Pdu(0x11));
    EXPECT_EQ(r.bytes, (std::vector<std::uint8_t>{0x11, 0x03, 0x42, 0x43, 0xFF}));
    EXPECT_EQ(r.decode_error, CodecError::Ok);
    c.run_indicator_on = false;
    DataModel off(c);
    EXPECT_EQ(call(off, Pdu(0x11)).bytes.back(), 0x00);
}

}  // namespace
}  // namespace mbstorm::slave::test
