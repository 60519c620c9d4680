// Response decoding: limits, exception responses, truncated and trailing bytes per function.
#include <gtest/gtest.h>

#include "codec/limits.hpp"
#include "pdu_test_support.hpp"

namespace mbstorm::codec::test {
namespace {

ByteVec read_response(std::uint8_t fc, std::size_t byte_count) {
    ByteVec v{fc, static_cast<std::uint8_t>(byte_count)};
    for (std::size_t i = 0; i < byte_count; ++i) v.push_back(static_cast<std::uint8_t>(i));
    return v;
}

void expect_truncations_fail(const ByteVec& pdu) {
    for (std::size_t n = 1; n < pdu.size(); ++n) {
        const CodecError e = decode_rsp(ByteVec(pdu.begin(), pdu.begin() + n));
        EXPECT_EQ(e, CodecError::Truncated) << to_hex(view(pdu)) << " cut at " << n;
    }
    ByteVec longer = pdu;
    longer.push_back(0);
    EXPECT_EQ(decode_rsp(longer), CodecError::TrailingBytes) << to_hex(view(pdu));
}

TEST(ResponseDecode, Empty) {
    EXPECT_EQ(decode_rsp(ByteVec{}), CodecError::Empty);
}

TEST(ResponseDecode, ReadBitsByteCountRange) {
    for (std::uint8_t fc : {0x01, 0x02}) {
        EXPECT_EQ(decode_rsp(read_response(fc, 0)), CodecError::QuantityOutOfRange);
        expect_response_round_trip(read_response(fc, 1));
        expect_response_round_trip(read_response(fc, 3));  // odd counts are fine for bits
        const Response r = expect_response_round_trip(read_response(fc, 250));
        EXPECT_EQ(r.payload.size(), 250u);
        EXPECT_EQ(decode_rsp(read_response(fc, 251)), CodecError::QuantityOutOfRange);
        expect_truncations_fail(read_response(fc, 5));
    }
}

TEST(ResponseDecode, ReadRegistersByteCountRange) {
    for (std::uint8_t fc : {0x03, 0x04, 0x17}) {
        EXPECT_EQ(decode_rsp(read_response(fc, 0)), CodecError::QuantityOutOfRange);
        expect_response_round_trip(read_response(fc, 2));
        EXPECT_EQ(decode_rsp(read_response(fc, 3)), CodecError::ByteCountMismatch);
        expect_response_round_trip(read_response(fc, 250));
        EXPECT_EQ(decode_rsp(read_response(fc, 251)), CodecError::QuantityOutOfRange);
        expect_truncations_fail(read_response(fc, 6));
    }
}

TEST(ResponseDecode, WriteSingleEchoes) {
    Response r = expect_response_round_trip(pdu_addr_qty(0x05, 0x00AC, 0xFF00));
    EXPECT_EQ(r.address, 0x00AC);
    EXPECT_EQ(r.value, 0xFF00);
    expect_response_round_trip(pdu_addr_qty(0x05, 0x00AC, 0x0000));
    EXPECT_EQ(decode_rsp(pdu_addr_qty(0x05, 0, 0x1234)), CodecError::InvalidCoilValue);
    r = expect_response_round_trip(pdu_addr_qty(0x06, 0xFFFF, 0x1234));
    EXPECT_EQ(r.value, 0x1234);
    expect_truncations_fail(pdu_addr_qty(0x05, 1, 0xFF00));
    expect_truncations_fail(pdu_addr_qty(0x06, 1, 2));
}

TEST(ResponseDecode, WriteMultipleEchoLimits) {
    for (auto [fc, max] : {std::pair<std::uint8_t, std::uint16_t>{0x0F, 1968}, {0x10, 123}}) {
        EXPECT_EQ(decode_rsp(pdu_addr_qty(fc, 0, 0)), CodecError::QuantityOutOfRange);
        expect_response_round_trip(pdu_addr_qty(fc, 0, 1));
        const Response r = expect_response_round_trip(pdu_addr_qty(fc, 7, max));
        EXPECT_EQ(r.address, 7);
        EXPECT_EQ(r.quantity, max);
        EXPECT_EQ(decode_rsp(pdu_addr_qty(fc, 0, max + 1)), CodecError::QuantityOutOfRange);
        EXPECT_EQ(decode_rsp(pdu_addr_qty(fc, 0xFFFF, 2)), CodecError::AddressOverflow);
        expect_truncations_fail(pdu_addr_qty(fc, 1, 1));
    }
}

TEST(ResponseDecode, ExceptionStatusAndCounters) {
    Response r = expect_response_round_trip(hex("07 6D"));
    EXPECT_EQ(r.exception_status, 0x6D);
    expect_truncations_fail(hex("07 6D"));
    r = expect_response_round_trip(hex("0B FF FF 01 08"));
    EXPECT_EQ(r.status, 0xFFFF);
    EXPECT_EQ(r.event_count, 0x0108);
    expect_truncations_fail(hex("0B FF FF 01 08"));
}

TEST(ResponseDecode, CommEventLog) {
    // Spec example: status 0, event count 0x0108, message count 0x0121, events 20 00.
    const ByteVec pdu = hex("0C 08 00 00 01 08 01 21 20 00");
    const Response r = expect_response_round_trip(pdu);
    EXPECT_EQ(r.status, 0);
    EXPECT_EQ(r.event_count, 0x0108);
    EXPECT_EQ(r.message_count, 0x0121);
    EXPECT_EQ(to_hex(r.payload), "20 00");
    expect_truncations_fail(pdu);
    expect_response_round_trip(hex("0C 06 FF FF 00 00 00 00"));  // no events
    EXPECT_EQ(decode_rsp(hex("0C 05 00 00 00 00 00")), CodecError::ByteCountMismatch);
    ByteVec most{0x0C, 70, 0, 0, 0, 1, 0, 2};
    most.resize(72, 0x20);
    expect_response_round_trip(most);  // 64 events
    most[1] = 71;
    most.push_back(0x20);
    EXPECT_EQ(decode_rsp(most), CodecError::QuantityOutOfRange);
}

TEST(ResponseDecode, Diagnostics) {
    const ByteVec echo = hex("08 00 00 A5 37");
    Response r = expect_response_round_trip(echo);
    EXPECT_EQ(to_hex(r.payload), "A5 37");
    expect_response_round_trip(hex("08 00 00"));
    const ByteVec counter = hex("08 00 0B 01 2C");
    r = expect_response_round_trip(counter);
    EXPECT_EQ(r.sub_function, 0x0B);
    EXPECT_EQ(to_hex(r.payload), "01 2C");
    expect_truncations_fail(hex("08 00 0B 01 2C"));
    EXPECT_EQ(decode_rsp(hex("08 00 13 00 00")), CodecError::UnsupportedSubFunction);
}

TEST(ResponseDecode, ReportServerId) {
    const ByteVec pdu = hex("11 03 0A FF 42");
    const Response r = expect_response_round_trip(pdu);
    EXPECT_EQ(to_hex(r.payload), "0A FF 42");
    expect_truncations_fail(hex("11 03 0A FF 42"));
    EXPECT_EQ(decode_rsp(hex("11 00")), CodecError::ByteCountMismatch);
    ByteVec big{0x11, 251};
    big.resize(253, 0x41);
    expect_response_round_trip(big);
    big[1] = 252;
    big.push_back(0x41);
    EXPECT_EQ(decode_rsp(big), CodecError::TrailingBytes);  // beyond the 253-byte PDU
}

TEST(ResponseDecode, ReadFileRecord) {
    // Spec example: two sub-responses of two registers each.
    const ByteVec pdu = hex("14 0C 05 06 0D FE 00 20 05 06 33 CD 00 40");
    const Response r = expect_response_round_trip(pdu);
    FileResponseIterator it(r.payload);
    FileSubResponse sub;
    ASSERT_EQ(it.next(sub), CodecError::Ok);
    EXPECT_EQ(sub.reference_type, 6);
    EXPECT_EQ(to_hex(sub.record_data), "0D FE 00 20");
    ASSERT_EQ(it.next(sub), CodecError::Ok);
    EXPECT_EQ(to_hex(sub.record_data), "33 CD 00 40");
    EXPECT_EQ(it.next(sub), CodecError::Empty);
    expect_truncations_fail(pdu);

    EXPECT_EQ(decode_rsp(hex("14 00")), CodecError::ByteCountMismatch);
    EXPECT_EQ(decode_rsp(hex("14 04 03 05 00 01")), CodecError::InvalidReferenceType);
    EXPECT_EQ(decode_rsp(hex("14 03 02 06 00")), CodecError::ByteCountMismatch);  // odd data
    EXPECT_EQ(decode_rsp(hex("14 02 01 06")), CodecError::ByteCountMismatch);     // no data
    EXPECT_EQ(decode_rsp(hex("14 04 00 06 00 01")), CodecError::ByteCountMismatch);
    EXPECT_EQ(decode_rsp(hex("14 04 05 06 00 01")), CodecError::ByteCountMismatch);
    // Sub-responses are always an even number of bytes, so 0xF4 is the largest usable count.
    ByteVec biggest{0x14, 0xF4, 0xF3, 0x06};
    biggest.resize(2 + 0xF4, 0x11);
    expect_response_round_trip(biggest);
    ByteVec over{0x14, 0xF6, 0xF5, 0x06};
    over.resize(2 + 0xF6, 0x11);
    EXPECT_EQ(decode_rsp(over), CodecError::ByteCountMismatch);
}

TEST(ResponseDecode, WriteFileRecordEcho) {
    const ByteVec pdu = hex("15 0D 06 00 04 00 07 00 03 06 AF 04 BE 10 0D");
    const Response r = expect_response_round_trip(pdu);
    FileRecordIterator it(r.payload, true);
    FileSubRequest sub;
    ASSERT_EQ(it.next(sub), CodecError::Ok);
    EXPECT_EQ(sub.file_number, 4);
    EXPECT_EQ(sub.record_number, 7);
    EXPECT_EQ(sub.record_length, 3);
    EXPECT_EQ(to_hex(sub.record_data), "06 AF 04 BE 10 0D");
    EXPECT_EQ(it.next(sub), CodecError::Empty);
    expect_truncations_fail(pdu);
    EXPECT_EQ(decode_rsp(hex("15 0D 05 00 04 00 07 00 03 06 AF 04 BE 10 0D")),
              CodecError::InvalidReferenceType);
}

TEST(ResponseDecode, MaskWriteEcho) {
    const Response r = expect_response_round_trip(hex("16 00 04 00 F2 00 25"));
    EXPECT_EQ(r.and_mask, 0xF2);
    EXPECT_EQ(r.or_mask, 0x25);
    expect_truncations_fail(hex("16 00 04 00 F2 00 25"));
}

ByteVec fifo_response(std::uint16_t count) {
    ByteVec v{0x18};
    put16(v, static_cast<std::uint16_t>(2 + 2 * count));
    put16(v, count);
    for (int i = 0; i < count; ++i) put16(v, static_cast<std::uint16_t>(i));
    return v;
}

TEST(ResponseDecode, FifoCountLimit) {
    Response r = expect_response_round_trip(fifo_response(0));
    EXPECT_EQ(r.fifo_count, 0);
    const ByteVec two = fifo_response(2);
    r = expect_response_round_trip(two);
    EXPECT_EQ(to_hex(r.payload), "00 00 00 01");
    expect_response_round_trip(fifo_response(31));
    EXPECT_EQ(decode_rsp(fifo_response(32)), CodecError::QuantityOutOfRange);
    expect_truncations_fail(fifo_response(2));
    ByteVec bad = fifo_response(2);
    bad[2] = 5;  // byte count disagrees with the FIFO count
    EXPECT_EQ(decode_rsp(bad), CodecError::ByteCountMismatch);
}

TEST(ResponseDecode, ReadDeviceIdentification) {
    // Basic stream: vendor, product code, revision.
    const ByteVec pdu = hex("2B 0E 01 01 00 00 03 00 05 41 42 43 44 45 01 02 50 31 02 03 56 31 2E");
    const Response r = expect_response_round_trip(pdu);
    EXPECT_EQ(r.device_id_code, 1);
    EXPECT_EQ(r.conformity_level, 1);
    EXPECT_EQ(r.object_count, 3);
    DeviceIdObjectIterator it(r.payload);
    DeviceIdObject o;
    ASSERT_EQ(it.next(o), CodecError::Ok);
    EXPECT_EQ(o.id, 0);
    EXPECT_EQ(to_hex(o.value), "41 42 43 44 45");
    ASSERT_EQ(it.next(o), CodecError::Ok);
    ASSERT_EQ(it.next(o), CodecError::Ok);
    EXPECT_EQ(o.id, 2);
    EXPECT_EQ(it.next(o), CodecError::Empty);
    expect_truncations_fail(pdu);

    expect_response_round_trip(hex("2B 0E 02 82 FF 03 00"));  // more follows, no objects yet
    EXPECT_EQ(decode_rsp(hex("2B 0E 00 01 00 00 00")), CodecError::InvalidDeviceIdCode);
    EXPECT_EQ(decode_rsp(hex("2B 0E 05 01 00 00 00")), CodecError::InvalidDeviceIdCode);
    EXPECT_EQ(decode_rsp(hex("2B 0D 01 01 00 00 00")), CodecError::UnsupportedSubFunction);
    EXPECT_EQ(decode_rsp(hex("2B 0E 01 01 00 00 02 00 01 41")), CodecError::Truncated);
    EXPECT_EQ(decode_rsp(hex("2B 0E 01 01 00 00 00 00 01 41")), CodecError::TrailingBytes);
}

TEST(ResponseDecode, UnsupportedFunction) {
    EXPECT_EQ(decode_rsp(hex("41 00")), CodecError::UnsupportedFunction);
    EXPECT_EQ(decode_rsp(hex("00")), CodecError::UnsupportedFunction);
}

// Every code the spec defines, on every function (exceptions echo any function code).
TEST(ResponseDecode, ExceptionResponses) {
    for (std::uint8_t code : {0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x08, 0x0A, 0x0B}) {
        for (int fc = 0; fc < 0x80; ++fc) {
            const ByteVec pdu{static_cast<std::uint8_t>(fc | 0x80), code};
            const Response r = expect_response_round_trip(pdu);
            EXPECT_EQ(r.function, fc);
            EXPECT_EQ(static_cast<std::uint8_t>(r.exception), code);
            EXPECT_TRUE(is_known_exception(code));
        }
    }
    EXPECT_EQ(decode_rsp(hex("83 00")), CodecError::InvalidExceptionCode);
    EXPECT_EQ(decode_rsp(hex("83")), CodecError::Truncated);
    EXPECT_EQ(decode_rsp(hex("83 02 00")), CodecError::TrailingBytes);
    // Codes the spec does not define still decode: a tester must see what came back.
    const Response odd = expect_response_round_trip(hex("83 7F"));
    EXPECT_FALSE(is_known_exception(0x7F));
    EXPECT_EQ(static_cast<std::uint8_t>(odd.exception), 0x7F);
}

TEST(ResponseDecode, OverlongPduRejected) {
    ByteVec big{0x08, 0x00, 0x00};
    big.resize(limits::kMaxPdu, 1);
    expect_response_round_trip(big);
    big.push_back(1);
    EXPECT_EQ(decode_rsp(big), CodecError::TrailingBytes);
}

}  // namespace
}  // namespace mbstorm::codec::test
