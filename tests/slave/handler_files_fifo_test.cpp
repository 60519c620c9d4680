// FC14/15 file records and FC18 FIFO queues.
#include <gtest/gtest.h>

#include "slave_test_support.hpp"

namespace mbstorm::slave::test {
namespace {

using codec::ExceptionCode;

TEST(HandlerFileRecords, WriteThenReadBack) {
    DataModel m(small_config());  // 4 files x 10000 records
    // Spec-shaped FC15: file 4, record 7, three registers.
    const auto write = Pdu(0x15).u8(13).u8(6).u16(4).u16(7).u16(3).words({0x06AF, 0x04BE, 0x100D});
    const Reply w = call(m, write);
    EXPECT_EQ(w.bytes, write.bytes());
    EXPECT_TRUE(w.result.wrote);
    EXPECT_EQ(m.files().get(4, 8), 0x04BE);

    m.files().set(3, 9, 0x0DFE);
    m.files().set(3, 10, 0x0020);
    // FC14: file 4 rec 7 len 3 ... and file 3 rec 9 len 2 (two sub-requests).
    const Reply r = call(m, Pdu(0x14).u8(14).u8(6).u16(4).u16(7).u16(3).u8(6).u16(3).u16(9).u16(2));
    ASSERT_EQ(r.result.outcome, Outcome::Response);
    const std::vector<std::uint8_t> want = {0x14, 0x0E, 0x07, 0x06, 0x06, 0xAF, 0x04, 0xBE,
                                            0x10, 0x0D, 0x05, 0x06, 0x0D, 0xFE, 0x00, 0x20};
    EXPECT_EQ(r.bytes, want);
    EXPECT_EQ(r.decode_error, codec::CodecError::Ok);
}

TEST(HandlerFileRecords, UnknownFileOrRecordRangeIs02) {
    DataModel m(small_config());
    // File 5 does not exist (4 files), file 0 never does.
    EXPECT_TRUE(call(m, Pdu(0x14).u8(7).u8(6).u16(5).u16(0).u16(1))
                    .is_exception(ExceptionCode::IllegalDataAddress));
    EXPECT_TRUE(call(m, Pdu(0x14).u8(7).u8(6).u16(0).u16(0).u16(1))
                    .is_exception(ExceptionCode::IllegalDataAddress));
    // Record 9999 is the last one.
    EXPECT_EQ(call(m, Pdu(0x14).u8(7).u8(6).u16(1).u16(9999).u16(1)).result.outcome,
              Outcome::Response);
    EXPECT_TRUE(call(m, Pdu(0x14).u8(7).u8(6).u16(1).u16(9999).u16(2))
                    .is_exception(ExceptionCode::IllegalDataAddress));
    // Reference type other than 6.
    EXPECT_TRUE(call(m, Pdu(0x14).u8(7).u8(5).u16(1).u16(0).u16(1))
                    .is_exception(ExceptionCode::IllegalDataAddress));
}

TEST(HandlerFileRecords, SmallerConfiguredFilesLimitTheRecords) {
    ModelConfig c = small_config();
    c.file_count = 2;
    c.file_records = 100;
    DataModel m(c);
    EXPECT_TRUE(call(m, Pdu(0x14).u8(7).u8(6).u16(3).u16(0).u16(1))
                    .is_exception(ExceptionCode::IllegalDataAddress));
    EXPECT_TRUE(call(m, Pdu(0x14).u8(7).u8(6).u16(2).u16(99).u16(2))
                    .is_exception(ExceptionCode::IllegalDataAddress));
    EXPECT_TRUE(call(m, Pdu(0x15).u8(9).u8(6).u16(2).u16(100).u16(1).u16(5))
                    .is_exception(ExceptionCode::IllegalDataAddress));
}

TEST(HandlerFileRecords, ByteCountProblemsAre03AndOutrank02) {
    DataModel m(small_config());
    // Byte count below 7.
    EXPECT_TRUE(call(m, Pdu(0x14).u8(6).u8(6).u16(1).u16(0).u8(0))
                    .is_exception(ExceptionCode::IllegalDataValue));
    // Byte count disagrees with the PDU.
    EXPECT_TRUE(call(m, Pdu(0x14).u8(8).u8(6).u16(1).u16(0).u16(1))
                    .is_exception(ExceptionCode::IllegalDataValue));
    // Response would not fit one PDU (2 x 125 registers), even though file 9 is also unknown.
    EXPECT_TRUE(call(m, Pdu(0x14).u8(14).u8(6).u16(9).u16(0).u16(125).u8(6).u16(1).u16(0).u16(125))
                    .is_exception(ExceptionCode::IllegalDataValue));
}

TEST(HandlerFileRecords, ABadSubRequestWritesNothing) {
    DataModel m(small_config());
    // First sub-request fine, second names file 77: neither may be applied.
    const Reply r = call(
        m, Pdu(0x15).u8(18).u8(6).u16(1).u16(0).u16(1).u16(0x1111).u8(6).u16(77).u16(0).u16(1).u16(
               0x2222));
    EXPECT_TRUE(r.is_exception(ExceptionCode::IllegalDataAddress));
    EXPECT_EQ(m.files().get(1, 0), 0);
}

TEST(HandlerFifo, ReturnsCountThenValuesWithoutConsuming) {
    DataModel m(small_config());
    const std::uint16_t values[] = {0x01B8, 0x1284};
    ASSERT_TRUE(m.fifo_set(0x04DE % 100, values));
    const auto req = Pdu(0x18).u16(0x04DE % 100);
    const Reply r = call(m, req);
    const std::vector<std::uint8_t> want = {0x18, 0x00, 0x06, 0x00, 0x02, 0x01, 0xB8, 0x12, 0x84};
    EXPECT_EQ(r.bytes, want);
    EXPECT_EQ(r.decode_error, codec::CodecError::Ok);
    EXPECT_EQ(r.decoded.fifo_count, 2);
    EXPECT_EQ(call(m, req).bytes, want);  // still there
}

TEST(HandlerFifo, EmptyAndFullQueues) {
    DataModel m(small_config());
    EXPECT_EQ(call(m, Pdu(0x18).u16(10)).bytes,
              (std::vector<std::uint8_t>{0x18, 0x00, 0x02, 0x00, 0x00}));
    for (unsigned i = 0; i < 31; ++i) ASSERT_TRUE(m.fifo_push(50, static_cast<std::uint16_t>(i)));
    EXPECT_FALSE(m.fifo_push(50, 99));  // 31 is the limit
    const Reply r = call(m, Pdu(0x18).u16(50));
    ASSERT_EQ(r.bytes.size(), 5u + 62u);
    EXPECT_EQ(codec::load_be16(r.bytes.data() + 1), 64);
    EXPECT_EQ(codec::load_be16(r.bytes.data() + 3), 31);
    EXPECT_EQ(codec::load_be16(r.bytes.data() + 5 + 60), 30);
    EXPECT_EQ(r.decode_error, codec::CodecError::Ok);
}

TEST(HandlerFifo, CountAbove31Is03AndPointerOrQueueOutsideIs02) {
    DataModel m(small_config(100));
    m.holding_registers().set(20, 32);
    EXPECT_TRUE(call(m, Pdu(0x18).u16(20)).is_exception(ExceptionCode::IllegalDataValue));
    EXPECT_TRUE(call(m, Pdu(0x18).u16(100)).is_exception(ExceptionCode::IllegalDataAddress));
    m.holding_registers().set(95, 10);  // values would need 96..105
    EXPECT_TRUE(call(m, Pdu(0x18).u16(95)).is_exception(ExceptionCode::IllegalDataAddress));
    EXPECT_TRUE(call(m, Pdu(0x18).u16(1).u8(0)).is_exception(ExceptionCode::IllegalDataValue));
}

}  // namespace
}  // namespace mbstorm::slave::test
