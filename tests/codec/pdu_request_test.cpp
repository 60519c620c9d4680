// Request decoding: every limit at 0, min, max and max+1, every exception path, and the
// 01 -> 03 -> 02 precedence of the spec's state diagrams.
#include <gtest/gtest.h>

#include "codec/limits.hpp"
#include "pdu_test_support.hpp"

namespace mbstorm::codec::test {
namespace {

constexpr auto kOk = CodecError::Ok;
constexpr auto kNone = ExceptionCode::None;
constexpr auto kFn = ExceptionCode::IllegalFunction;
constexpr auto kAddr = ExceptionCode::IllegalDataAddress;
constexpr auto kVal = ExceptionCode::IllegalDataValue;

struct ReadLimit {
    std::uint8_t fc;
    std::uint16_t max;
};

class ReadRequestLimits : public ::testing::TestWithParam<ReadLimit> {};

TEST_P(ReadRequestLimits, QuantityZeroMinMaxAndMaxPlusOne) {
    const auto [fc, max] = GetParam();
    EXPECT_REQUEST_FAILS(pdu_addr_qty(fc, 0, 0), CodecError::QuantityOutOfRange, kVal);
    expect_request_round_trip(pdu_addr_qty(fc, 0, 1));
    expect_request_round_trip(pdu_addr_qty(fc, 0, max));
    EXPECT_REQUEST_FAILS(pdu_addr_qty(fc, 0, max + 1), CodecError::QuantityOutOfRange, kVal);
    EXPECT_REQUEST_FAILS(pdu_addr_qty(fc, 0, 0xFFFF), CodecError::QuantityOutOfRange, kVal);
}

TEST_P(ReadRequestLimits, AddressRangeEndsAtFFFF) {
    const auto [fc, max] = GetParam();
    expect_request_round_trip(pdu_addr_qty(fc, 0xFFFF, 1));
    EXPECT_REQUEST_FAILS(pdu_addr_qty(fc, 0xFFFF, 2), CodecError::AddressOverflow, kAddr);
    expect_request_round_trip(pdu_addr_qty(fc, static_cast<std::uint16_t>(0x10000 - max), max));
    EXPECT_REQUEST_FAILS(pdu_addr_qty(fc, static_cast<std::uint16_t>(0x10001 - max), max),
                         CodecError::AddressOverflow, kAddr);
}

TEST_P(ReadRequestLimits, BadQuantityOutranksBadAddress) {
    const auto [fc, max] = GetParam();
    EXPECT_REQUEST_FAILS(pdu_addr_qty(fc, 0xFFFF, max + 1), CodecError::QuantityOutOfRange, kVal);
}

TEST_P(ReadRequestLimits, TruncatedAndTrailing) {
    const auto [fc, max] = GetParam();
    ByteVec pdu = pdu_addr_qty(fc, 1, 1);
    for (std::size_t n = 1; n < pdu.size(); ++n) {
        EXPECT_REQUEST_FAILS(ByteVec(pdu.begin(), pdu.begin() + n), CodecError::Truncated, kVal);
    }
    pdu.push_back(0);
    EXPECT_REQUEST_FAILS(pdu, CodecError::TrailingBytes, kVal);
}

TEST_P(ReadRequestLimits, FieldsDecoded) {
    const auto [fc, max] = GetParam();
    const Request r = expect_request_round_trip(pdu_addr_qty(fc, 0x1234, 7));
    EXPECT_EQ(r.function, fc);
    EXPECT_EQ(r.address, 0x1234);
    EXPECT_EQ(r.quantity, 7);
    EXPECT_TRUE(r.payload.empty());
}

INSTANTIATE_TEST_SUITE_P(AllReads, ReadRequestLimits,
                         ::testing::Values(ReadLimit{0x01, 2000}, ReadLimit{0x02, 2000},
                                           ReadLimit{0x03, 125}, ReadLimit{0x04, 125}));

TEST(RequestDecode, EmptyOwesNoException) {
    EXPECT_REQUEST_FAILS(ByteVec{}, CodecError::Empty, kNone);
}

TEST(RequestDecode, UnsupportedFunctionsOweIllegalFunction) {
    for (int fc = 0; fc < 256; ++fc) {
        const auto b = static_cast<std::uint8_t>(fc);
        if (is_supported_function(b)) continue;
        EXPECT_REQUEST_FAILS(ByteVec{b}, CodecError::UnsupportedFunction, kFn);
        // 01 outranks every other check: even a broken body gets 01.
        EXPECT_REQUEST_FAILS((ByteVec{b, 0, 0, 0, 0}), CodecError::UnsupportedFunction, kFn);
    }
}

TEST(RequestDecode, WriteSingleCoilAcceptsOnlyOnAndOff) {
    expect_request_round_trip(pdu_addr_qty(0x05, 0xFFFF, 0xFF00));
    expect_request_round_trip(pdu_addr_qty(0x05, 0, 0x0000));
    for (std::uint16_t v : {0x0001, 0x00FF, 0xFF01, 0xFFFF, 0x0100, 0xFE00}) {
        EXPECT_REQUEST_FAILS(pdu_addr_qty(0x05, 0, v), CodecError::InvalidCoilValue, kVal);
    }
    const Request r = expect_request_round_trip(pdu_addr_qty(0x05, 0x00AC, 0xFF00));
    EXPECT_EQ(r.address, 0x00AC);
    EXPECT_EQ(r.value, 0xFF00);
}

TEST(RequestDecode, FixedSizeFunctionsRejectTruncatedAndTrailing) {
    const ByteVec valid[] = {
        pdu_addr_qty(0x05, 1, 0xFF00),
        pdu_addr_qty(0x06, 1, 0x1234),
        ByteVec{0x07},
        ByteVec{0x0B},
        ByteVec{0x0C},
        ByteVec{0x11},
        hex("16 00 04 00 F2 00 25"),
        hex("18 04 DE"),
        hex("2B 0E 01 00"),
        hex("08 00 0A 00 00"),
    };
    for (const ByteVec& pdu : valid) {
        expect_request_round_trip(pdu);
        for (std::size_t n = 1; n < pdu.size(); ++n) {
            const auto st = decode_req(ByteVec(pdu.begin(), pdu.begin() + n));
            EXPECT_EQ(st.error, CodecError::Truncated) << to_hex(view(pdu)) << " cut at " << n;
            EXPECT_EQ(st.exception, kVal);
        }
        ByteVec longer = pdu;
        longer.push_back(0x00);
        EXPECT_REQUEST_FAILS(longer, CodecError::TrailingBytes, kVal);
    }
}

TEST(RequestDecode, WriteSingleRegisterAnyValue) {
    for (std::uint16_t v : {0x0000, 0x0001, 0x7FFF, 0xFFFF}) {
        const Request r = expect_request_round_trip(pdu_addr_qty(0x06, 0xFFFF, v));
        EXPECT_EQ(r.value, v);
    }
}

struct WriteLimit {
    std::uint8_t fc;
    std::uint16_t max;
    bool coils;
};

class WriteMultipleLimits : public ::testing::TestWithParam<WriteLimit> {
  protected:
    static std::size_t bytes_for(const WriteLimit& w, std::uint16_t q) {
        return w.coils ? (q + 7u) / 8u : 2u * q;
    }
    static ByteVec pdu(const WriteLimit& w, std::uint16_t a, std::uint16_t q) {
        return pdu_write_multiple(w.fc, a, q, bytes_for(w, q) & 0xFF);
    }
};

TEST_P(WriteMultipleLimits, QuantityZeroMinMaxAndMaxPlusOne) {
    const WriteLimit w = GetParam();
    EXPECT_REQUEST_FAILS(pdu_write_multiple(w.fc, 0, 0, 0), CodecError::QuantityOutOfRange, kVal);
    EXPECT_REQUEST_FAILS(pdu_write_multiple(w.fc, 0, 0, 1), CodecError::QuantityOutOfRange, kVal);
    expect_request_round_trip(pdu(w, 0, 1));
    const Request r = expect_request_round_trip(pdu(w, 0, w.max));
    EXPECT_EQ(r.payload.size(), bytes_for(w, w.max));
    EXPECT_REQUEST_FAILS(pdu(w, 0, w.max + 1), CodecError::QuantityOutOfRange, kVal);
}

TEST_P(WriteMultipleLimits, ByteCountMustMatchQuantity) {
    const WriteLimit w = GetParam();
    for (std::uint16_t q : {std::uint16_t{1}, std::uint16_t{9}, w.max}) {
        const std::size_t right = bytes_for(w, q);
        EXPECT_REQUEST_FAILS(pdu_write_multiple(w.fc, 0, q, right - 1),
                             CodecError::ByteCountMismatch, kVal);
        EXPECT_REQUEST_FAILS(pdu_write_multiple(w.fc, 0, q, right + 1),
                             CodecError::ByteCountMismatch, kVal);
    }
}

TEST_P(WriteMultipleLimits, TruncatedAndTrailing) {
    const WriteLimit w = GetParam();
    ByteVec full = pdu(w, 10, 9);
    for (std::size_t n = 1; n < full.size(); ++n) {
        EXPECT_REQUEST_FAILS(ByteVec(full.begin(), full.begin() + n), CodecError::Truncated, kVal);
    }
    full.push_back(0);
    EXPECT_REQUEST_FAILS(full, CodecError::TrailingBytes, kVal);
}

TEST_P(WriteMultipleLimits, AddressRangeAndPrecedence) {
    const WriteLimit w = GetParam();
    expect_request_round_trip(pdu(w, 0xFFFF, 1));
    EXPECT_REQUEST_FAILS(pdu(w, 0xFFFF, 2), CodecError::AddressOverflow, kAddr);
    expect_request_round_trip(pdu(w, static_cast<std::uint16_t>(0x10000 - w.max), w.max));
    // 03 (bad byte count, bad length) outranks 02 (address).
    EXPECT_REQUEST_FAILS(pdu_write_multiple(w.fc, 0xFFFF, 2, bytes_for(w, 2) + 1),
                         CodecError::ByteCountMismatch, kVal);
    ByteVec cut = pdu(w, 0xFFFF, 2);
    cut.pop_back();
    EXPECT_REQUEST_FAILS(cut, CodecError::Truncated, kVal);
}

INSTANTIATE_TEST_SUITE_P(Fc0FAnd10, WriteMultipleLimits,
                         ::testing::Values(WriteLimit{0x0F, 1968, true},
                                           WriteLimit{0x10, 123, false}));

TEST(RequestDecode, WriteMultipleCoilsFields) {
    const ByteVec pdu = hex("0F 00 13 00 0A 02 CD 01");
    const Request r = expect_request_round_trip(pdu);
    EXPECT_EQ(r.address, 0x13);
    EXPECT_EQ(r.quantity, 10);
    EXPECT_EQ(to_hex(r.payload), "CD 01");
}

TEST(RequestDecode, ReadWriteMultipleLimits) {
    expect_request_round_trip(pdu_read_write(0, 1, 0, 1));
    expect_request_round_trip(pdu_read_write(0, 125, 0, 121));
    EXPECT_REQUEST_FAILS(pdu_read_write(0, 0, 0, 1), CodecError::QuantityOutOfRange, kVal);
    EXPECT_REQUEST_FAILS(pdu_read_write(0, 126, 0, 1), CodecError::QuantityOutOfRange, kVal);
    EXPECT_REQUEST_FAILS(pdu_read_write(0, 1, 0, 0), CodecError::QuantityOutOfRange, kVal);
    EXPECT_REQUEST_FAILS(pdu_read_write(0, 1, 0, 122), CodecError::QuantityOutOfRange, kVal);
    // Address checks on both halves, after the value checks.
    expect_request_round_trip(pdu_read_write(0xFF83, 125, 0xFF87, 121));
    EXPECT_REQUEST_FAILS(pdu_read_write(0xFF84, 125, 0, 1), CodecError::AddressOverflow, kAddr);
    EXPECT_REQUEST_FAILS(pdu_read_write(0, 1, 0xFF88, 121), CodecError::AddressOverflow, kAddr);
    EXPECT_REQUEST_FAILS(pdu_read_write(0xFFFF, 126, 0, 1), CodecError::QuantityOutOfRange, kVal);

    ByteVec bad_count = pdu_read_write(0, 1, 0, 2);
    bad_count[9] = 3;
    bad_count.pop_back();
    EXPECT_REQUEST_FAILS(bad_count, CodecError::ByteCountMismatch, kVal);

    ByteVec full = pdu_read_write(3, 4, 5, 2);
    const Request r = expect_request_round_trip(full);
    EXPECT_EQ(r.address, 3);
    EXPECT_EQ(r.quantity, 4);
    EXPECT_EQ(r.write_address, 5);
    EXPECT_EQ(r.write_quantity, 2);
    EXPECT_EQ(r.payload.size(), 4u);
    EXPECT_EQ(expected_read_byte_count(r), 8);
    for (std::size_t n = 1; n < full.size(); ++n) {
        EXPECT_REQUEST_FAILS(ByteVec(full.begin(), full.begin() + n), CodecError::Truncated, kVal);
    }
    full.push_back(0);
    EXPECT_REQUEST_FAILS(full, CodecError::TrailingBytes, kVal);
}

TEST(RequestDecode, MaskWriteFields) {
    const Request r = expect_request_round_trip(hex("16 00 04 00 F2 00 25"));
    EXPECT_EQ(r.address, 4);
    EXPECT_EQ(r.and_mask, 0x00F2);
    EXPECT_EQ(r.or_mask, 0x0025);
}

TEST(RequestDecode, FifoPointer) {
    const Request r = expect_request_round_trip(hex("18 04 DE"));
    EXPECT_EQ(r.address, 0x04DE);
}

TEST(RequestDecode, DiagnosticsReturnQueryDataTakesAnyData) {
    expect_request_round_trip(hex("08 00 00"));
    const ByteVec pdu = hex("08 00 00 A5 37");
    const Request r = expect_request_round_trip(pdu);
    EXPECT_EQ(r.sub_function, 0);
    EXPECT_EQ(to_hex(r.payload), "A5 37");
    expect_request_round_trip(hex("08 00 00 01 02 03"));
    ByteVec biggest = hex("08 00 00");
    biggest.resize(limits::kMaxPdu, 0x5A);
    expect_request_round_trip(biggest);
    biggest.push_back(0);
    EXPECT_REQUEST_FAILS(biggest, CodecError::TrailingBytes, kVal);
}

TEST(RequestDecode, DiagnosticsCountersTakeOneWord) {
    for (std::uint16_t sub = 0x0A; sub <= 0x14; ++sub) {
        ByteVec pdu{0x08};
        put16(pdu, sub);
        put16(pdu, 0x0000);
        if (sub == 0x13) {  // reserved by the spec
            EXPECT_REQUEST_FAILS(pdu, CodecError::UnsupportedSubFunction, kFn);
            continue;
        }
        const Request r = expect_request_round_trip(pdu);
        EXPECT_EQ(r.sub_function, sub);
        EXPECT_REQUEST_FAILS(ByteVec(pdu.begin(), pdu.end() - 1), CodecError::Truncated, kVal);
        EXPECT_REQUEST_FAILS(ByteVec(pdu.begin(), pdu.end() - 2), CodecError::Truncated, kVal);
        pdu.push_back(0);
        EXPECT_REQUEST_FAILS(pdu, CodecError::TrailingBytes, kVal);
    }
}

TEST(RequestDecode, DiagnosticsUnknownSubFunctionOwesIllegalFunction) {
    for (std::uint16_t sub : {0x0005, 0x0009, 0x0013, 0x0015, 0x00FF, 0xFFFF}) {
        ByteVec pdu{0x08};
        put16(pdu, sub);
        put16(pdu, 0);
        EXPECT_REQUEST_FAILS(pdu, CodecError::UnsupportedSubFunction, kFn);
    }
    EXPECT_REQUEST_FAILS(hex("08 00"), CodecError::Truncated, kVal);
    EXPECT_REQUEST_FAILS(hex("08"), CodecError::Truncated, kVal);
}

TEST(RequestDecode, ReadDeviceIdCodes) {
    EXPECT_REQUEST_FAILS(hex("2B 0E 00 00"), CodecError::InvalidDeviceIdCode, kVal);
    for (std::uint8_t code = 1; code <= 4; ++code) {
        const Request r = expect_request_round_trip(ByteVec{0x2B, 0x0E, code, 0x80});
        EXPECT_EQ(r.mei_type, 0x0E);
        EXPECT_EQ(r.device_id_code, code);
        EXPECT_EQ(r.object_id, 0x80);
    }
    EXPECT_REQUEST_FAILS(hex("2B 0E 05 00"), CodecError::InvalidDeviceIdCode, kVal);
    EXPECT_REQUEST_FAILS(hex("2B 0E FF 00"), CodecError::InvalidDeviceIdCode, kVal);
    // Any object id is the server's business, even for code 4.
    expect_request_round_trip(hex("2B 0E 04 FF"));
}

TEST(RequestDecode, OtherMeiTypesOweIllegalFunction) {
    EXPECT_REQUEST_FAILS(hex("2B 0D 00 00"), CodecError::UnsupportedSubFunction, kFn);
    EXPECT_REQUEST_FAILS(hex("2B 00"), CodecError::UnsupportedSubFunction, kFn);
    EXPECT_REQUEST_FAILS(hex("2B"), CodecError::Truncated, kVal);
}

// --- FC14 / FC15 -------------------------------------------------------------------------

ByteVec read_file_request(int subs, std::uint16_t length = 1) {
    ByteVec s;
    for (int i = 0; i < subs; ++i)
        add_file_sub(s, 6, 4, static_cast<std::uint16_t>(i), length, false);
    return pdu_file(0x14, s);
}

TEST(RequestDecode, ReadFileByteCountRange) {
    EXPECT_REQUEST_FAILS(hex("14 00"), CodecError::ByteCountMismatch, kVal);
    ByteVec six = hex("14 06 06 00 04 00 01 00");
    EXPECT_REQUEST_FAILS(six, CodecError::ByteCountMismatch, kVal);
    expect_request_round_trip(read_file_request(1));   // 0x07
    expect_request_round_trip(read_file_request(35));  // 0xF5
    ByteVec too_big = read_file_request(36);           // 0xFC
    EXPECT_REQUEST_FAILS(too_big, CodecError::ByteCountMismatch, kVal);
    // Not a whole number of 7-byte sub-requests.
    ByteVec ragged = read_file_request(1);
    ragged.push_back(0x06);
    ragged[1] = 8;
    EXPECT_REQUEST_FAILS(ragged, CodecError::ByteCountMismatch, kVal);
}

TEST(RequestDecode, ReadFileTruncatedAndTrailing) {
    ByteVec full = read_file_request(2);
    for (std::size_t n = 1; n < full.size(); ++n) {
        EXPECT_REQUEST_FAILS(ByteVec(full.begin(), full.begin() + n), CodecError::Truncated, kVal);
    }
    full.push_back(0);
    EXPECT_REQUEST_FAILS(full, CodecError::TrailingBytes, kVal);
}

TEST(RequestDecode, ReadFileRecordLimits) {
    // Record length 0 asks for nothing: 03.
    EXPECT_REQUEST_FAILS(read_file_request(1, 0), CodecError::QuantityOutOfRange, kVal);
    // The answer must fit its 0xF5-byte length: 2 + 2 * 121 = 244 fits, 2 + 2 * 122 does not.
    expect_request_round_trip(read_file_request(1, 121));
    EXPECT_REQUEST_FAILS(read_file_request(1, 122), CodecError::QuantityOutOfRange, kVal);
    EXPECT_REQUEST_FAILS(read_file_request(2, 61), CodecError::QuantityOutOfRange, kVal);
    expect_request_round_trip(read_file_request(2, 60));
}

TEST(RequestDecode, ReadFileAddressChecksOwe02) {
    ByteVec s;
    add_file_sub(s, 5, 4, 1, 2, false);
    EXPECT_REQUEST_FAILS(pdu_file(0x14, s), CodecError::InvalidReferenceType, kAddr);
    s.clear();
    add_file_sub(s, 6, 0, 1, 2, false);  // file numbers start at 1
    EXPECT_REQUEST_FAILS(pdu_file(0x14, s), CodecError::AddressOverflow, kAddr);
    s.clear();
    add_file_sub(s, 6, 0xFFFF, 0x270F, 1, false);  // last record of the last file
    expect_request_round_trip(pdu_file(0x14, s));
    s.clear();
    add_file_sub(s, 6, 1, 0x270F, 2, false);
    EXPECT_REQUEST_FAILS(pdu_file(0x14, s), CodecError::AddressOverflow, kAddr);
    s.clear();
    add_file_sub(s, 6, 1, 0x2710, 1, false);
    EXPECT_REQUEST_FAILS(pdu_file(0x14, s), CodecError::AddressOverflow, kAddr);
    // A bad value in a later sub-request outranks a bad address in an earlier one.
    s.clear();
    add_file_sub(s, 7, 1, 0, 1, false);
    add_file_sub(s, 6, 1, 0, 0, false);
    EXPECT_REQUEST_FAILS(pdu_file(0x14, s), CodecError::QuantityOutOfRange, kVal);
}

TEST(RequestDecode, WriteFileByteCountRange) {
    ByteVec s;
    add_file_sub(s, 6, 4, 7, 1, true);  // 9 bytes: the smallest
    const Request r = expect_request_round_trip(pdu_file(0x15, s));
    EXPECT_EQ(r.payload.size(), 9u);
    s.clear();
    add_file_sub(s, 6, 4, 7, 122, true);  // 7 + 244 = 0xFB: the largest
    expect_request_round_trip(pdu_file(0x15, s));
    s.clear();
    add_file_sub(s, 6, 4, 7, 123, true);  // 0xFD
    EXPECT_REQUEST_FAILS(pdu_file(0x15, s), CodecError::ByteCountMismatch, kVal);
    EXPECT_REQUEST_FAILS(hex("15 08 06 00 04 00 07 00 00 00"), CodecError::ByteCountMismatch, kVal);
    EXPECT_REQUEST_FAILS(hex("15 00"), CodecError::ByteCountMismatch, kVal);
}

TEST(RequestDecode, WriteFileShapeAndAddress) {
    ByteVec s;
    add_file_sub(s, 6, 4, 7, 2, true);
    add_file_sub(s, 6, 5, 9, 1, true);
    ByteVec full = pdu_file(0x15, s);
    expect_request_round_trip(full);
    for (std::size_t n = 1; n < full.size(); ++n) {
        EXPECT_REQUEST_FAILS(ByteVec(full.begin(), full.begin() + n), CodecError::Truncated, kVal);
    }
    full.push_back(0);
    EXPECT_REQUEST_FAILS(full, CodecError::TrailingBytes, kVal);

    // Record length claims more data than the byte count holds.
    ByteVec lying = hex("15 0B 06 00 04 00 07 00 03 00 01 00 02");
    EXPECT_REQUEST_FAILS(lying, CodecError::ByteCountMismatch, kVal);
    EXPECT_REQUEST_FAILS(hex("15 0A 06 00 04 00 07 00 01 AA BB CC"), CodecError::ByteCountMismatch,
                         kVal);
    s.clear();
    add_file_sub(s, 6, 4, 7, 0, true);
    add_file_sub(s, 6, 4, 7, 1, true);
    EXPECT_REQUEST_FAILS(pdu_file(0x15, s), CodecError::QuantityOutOfRange, kVal);
    s.clear();
    add_file_sub(s, 0, 4, 7, 1, true);
    EXPECT_REQUEST_FAILS(pdu_file(0x15, s), CodecError::InvalidReferenceType, kAddr);
    s.clear();
    add_file_sub(s, 6, 4, 0x270E, 3, true);
    EXPECT_REQUEST_FAILS(pdu_file(0x15, s), CodecError::AddressOverflow, kAddr);
}

TEST(RequestDecode, ExpectedReadByteCount) {
    Request r;
    r.function = 0x01;
    r.quantity = 37;
    EXPECT_EQ(expected_read_byte_count(r), 5);
    r.quantity = 2000;
    EXPECT_EQ(expected_read_byte_count(r), 250);
    r.function = 0x02;
    r.quantity = 8;
    EXPECT_EQ(expected_read_byte_count(r), 1);
    r.function = 0x03;
    r.quantity = 125;
    EXPECT_EQ(expected_read_byte_count(r), 250);
    r.function = 0x04;
    r.quantity = 1;
    EXPECT_EQ(expected_read_byte_count(r), 2);
    r.function = 0x06;
    EXPECT_EQ(expected_read_byte_count(r), -1);
}

TEST(RequestDecode, FailureLeavesFunctionSet) {
    Request r;
    r.address = 99;
    EXPECT_FALSE(decode_request(view(hex("03 00")), r).ok());
    EXPECT_EQ(r.function, 0x03);
    EXPECT_EQ(r.address, 0);  // reset, not stale
}

TEST(RequestDecode, SucceedsOnlyWithNoException) {
    EXPECT_EQ(decode_req(pdu_addr_qty(3, 0, 1)).error, kOk);
}

}  // namespace
}  // namespace mbstorm::codec::test
