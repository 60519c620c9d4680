// FC03/FC04 reads take a shortcut past the general decoder (handler.hpp, read_registers_inline):
// these check that every read, taken or refused by the shortcut, is answered as the spec and
// the general path say, with the same diagnostics, around every edge the shortcut tests.
#include <gtest/gtest.h>

#include "slave_test_support.hpp"

namespace mbstorm::slave::test {
namespace {

using codec::ExceptionCode;

// What the spec owes a 5-byte FC03/04 request on a table of `size` registers.
ExceptionCode owed(std::uint32_t size, std::uint16_t address, std::uint16_t quantity) {
    if (quantity == 0 || quantity > 125) return ExceptionCode::IllegalDataValue;
    if (std::uint32_t{address} + quantity > size) return ExceptionCode::IllegalDataAddress;
    return ExceptionCode::None;
}

void fill(RegisterTable& t) {
    for (std::uint32_t a = 0; a < t.size(); ++a)
        t.set(static_cast<std::uint16_t>(a), static_cast<std::uint16_t>(0xA500 + a * 3));
}

TEST(HandlerReadFastPath, EveryQuantityAndEdgeAddressIsAnsweredAsTheSpecSays) {
    for (std::uint32_t size : {0u, 1u, 100u, 125u, 65536u}) {
        ModelConfig config = small_config(size);
        config.sizes.holding_registers = size;
        config.sizes.input_registers = size;
        DataModel m(config);
        fill(m.holding_registers());
        fill(m.input_registers());
        std::vector<std::uint32_t> addresses = {0, 1, 65535, 65535 - 124, 65535 - 125};
        for (std::uint32_t d : {0u, 1u, 2u, 124u, 125u, 126u}) {
            if (size >= d) addresses.push_back(size - d);
        }
        for (unsigned fc : {0x03u, 0x04u}) {
            const RegisterTable& t = fc == 0x03 ? m.holding_registers() : m.input_registers();
            for (std::uint32_t address : addresses) {
                if (address > 0xFFFF) continue;
                for (unsigned quantity : {0u, 1u, 2u, 3u, 10u, 124u, 125u, 126u, 0xFFFFu}) {
                    const auto a = static_cast<std::uint16_t>(address);
                    const auto q = static_cast<std::uint16_t>(quantity);
                    const Reply r = call(m, Pdu(static_cast<std::uint8_t>(fc)).u16(a).u16(q));
                    const ExceptionCode code = owed(size, a, q);
                    SCOPED_TRACE(testing::Message() << "size " << size << " fc " << fc
                                                    << " address " << a << " quantity " << q);
                    if (code != ExceptionCode::None) {
                        EXPECT_TRUE(r.is_exception(code));
                        continue;
                    }
                    ASSERT_EQ(r.result.outcome, Outcome::Response);
                    EXPECT_EQ(r.result.function, fc);
                    EXPECT_FALSE(r.result.wrote);
                    ASSERT_EQ(r.bytes.size(), 2u + 2u * q);
                    EXPECT_EQ(r.bytes[0], fc);
                    EXPECT_EQ(r.bytes[1], 2 * q);
                    for (unsigned i = 0; i < q; ++i)
                        ASSERT_EQ(r.reg(i), t.get(static_cast<std::uint16_t>(a + i))) << i;
                }
            }
        }
    }
}

TEST(HandlerReadFastPath, OtherLengthsAndFunctionsTakeTheGeneralPath) {
    DataModel m(small_config());
    EXPECT_TRUE(
        call(m, Pdu(0x03).u16(0).u16(1).u8(0)).is_exception(ExceptionCode::IllegalDataValue));
    EXPECT_TRUE(call(m, Pdu(0x04).u16(0).u8(1)).is_exception(ExceptionCode::IllegalDataValue));
    EXPECT_EQ(call(m, Pdu(0x01).u16(0).u16(9)).bytes.size(), 4u);  // 2 bytes of coils
    EXPECT_EQ(call(m, Pdu(0x02).u16(0).u16(8)).bytes.size(), 3u);
}

TEST(HandlerReadFastPath, ReadsCountInTheDiagnosticsAndTheEventLog) {
    DataModel m(small_config());
    call(m, Pdu(0x03).u16(0).u16(10));   // shortcut
    call(m, Pdu(0x04).u16(90).u16(10));  // shortcut, last registers
    call(m, Pdu(0x03).u16(95).u16(10));  // 02, general path
    const Reply count = call(m, Pdu(0x0B));
    // Status word, then the event counter: 4 messages, one exception, the FC0B fetch itself.
    EXPECT_EQ(codec::load_be16(count.bytes.data() + 3), 2);
    const Reply log = call(m, Pdu(0x0C));
    ASSERT_EQ(log.result.outcome, Outcome::Response);
    // Byte count, status, event count, message count (5, this fetch included), then events
    // most recent first: FC0B's (receive, send), the 02's (receive, send with the exception
    // bit), then the two reads'.
    EXPECT_EQ(codec::load_be16(log.bytes.data() + 6), 5);
    const std::vector<std::uint8_t> events(log.bytes.begin() + 8, log.bytes.end());
    const std::vector<std::uint8_t> expected = {0x40, 0x80, 0x41, 0x80, 0x40, 0x80, 0x40, 0x80};
    EXPECT_EQ(events, expected);
}

TEST(HandlerReadFastPath, ReadCountersStillAdvanceBeforeTheRead) {
    DataModel m(small_config());
    m.holding_registers().add_read_counter(5, 2);
    EXPECT_EQ(call(m, Pdu(0x03).u16(0).u16(10)).reg(5), 2);
    EXPECT_EQ(call(m, Pdu(0x03).u16(5).u16(1)).reg(0), 4);
    EXPECT_EQ(call(m, Pdu(0x03).u16(6).u16(3)).reg(0), 0);  // not covered: not bumped
    EXPECT_EQ(m.holding_registers().get(5), 4);
}

TEST(HandlerReadFastPath, PerUnitModelsTakeTheShortcutForTheirOwnTables) {
    ModelConfig config = small_config();
    UnitModels units = UnitModels::per_unit(config, std::vector<std::uint8_t>{1, 2});
    units.find(1)->holding_registers().set(3, 0x1111);
    units.find(2)->holding_registers().set(3, 0x2222);
    EXPECT_EQ(call(units, 1, Pdu(0x03).u16(3).u16(1)).reg(0), 0x1111);
    EXPECT_EQ(call(units, 2, Pdu(0x03).u16(3).u16(1)).reg(0), 0x2222);
    EXPECT_TRUE(call(units, 7, Pdu(0x03).u16(3).u16(1))
                    .is_exception(ExceptionCode::GatewayTargetFailedToRespond));
    EXPECT_EQ(units.find(1)->diagnostics().message_count(), 1);
}

TEST(HandlerReadFastPath, WithoutDiagnosticsNothingIsCounted) {
    ModelConfig config = small_config();
    config.track_diagnostics = false;
    DataModel m(config);
    EXPECT_EQ(call(m, Pdu(0x03).u16(0).u16(10)).bytes.size(), 22u);
    EXPECT_EQ(m.diagnostics().message_count(), 0);
}

}  // namespace
}  // namespace mbstorm::slave::test
