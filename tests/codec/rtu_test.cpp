// RTU: CRC-16/MODBUS, frame encode/decode, length inference.
#include <gtest/gtest.h>

#include <array>
#include <cstring>
#include <random>

#include "codec/rtu.hpp"
#include "framing_test_support.hpp"

namespace mbstorm::codec {
namespace {

using framing_test::ByteVec;
using framing_test::hex_bytes;
using framing_test::to_vec;
using LenStatus = RtuLength::Status;

// Bit-at-a-time reference, straight from the definition.
std::uint16_t crc16_reference(Bytes data) {
    std::uint16_t crc = 0xFFFF;
    for (std::uint8_t b : data) {
        crc ^= b;
        for (int i = 0; i < 8; ++i) crc = (crc & 1) ? (crc >> 1) ^ 0xA001 : crc >> 1;
    }
    return crc;
}

TEST(Crc16, CheckValue) {
    const char* s = "123456789";
    EXPECT_EQ(crc16(Bytes(reinterpret_cast<const std::uint8_t*>(s), 9)), 0x4B37);
    EXPECT_EQ(crc16({}), 0xFFFF);
}

TEST(Crc16, MatchesBitwiseReferenceForEveryLengthAndAlignment) {
    std::mt19937 rng(12345);
    ByteVec data(600);
    for (auto& b : data) b = static_cast<std::uint8_t>(rng());
    for (std::size_t offset = 0; offset < 8; ++offset) {
        for (std::size_t n = 0; n + offset <= data.size(); n += (n < 40 ? 1 : 13)) {
            const Bytes piece(data.data() + offset, n);
            ASSERT_EQ(crc16(piece), crc16_reference(piece)) << offset << " " << n;
        }
    }
}

TEST(Crc16, ContinuesAcrossPieces) {
    const ByteVec a = hex_bytes("11 03 00 6B 00 03 01 02 03 04 05 06 07 08 09 0A 0B");
    for (std::size_t cut = 0; cut <= a.size(); ++cut) {
        const std::uint16_t first = crc16(Bytes(a.data(), cut));
        EXPECT_EQ(crc16(Bytes(a.data() + cut, a.size() - cut), first), crc16(a));
    }
}

TEST(Crc16, FrameWithItsCrcLeavesZeroResidue) {
    // Appending the CRC low byte first makes the CRC of the whole frame 0.
    EXPECT_EQ(crc16(hex_bytes("11 03 00 6B 00 03 76 87")), 0);
}

TEST(RtuEncode, AppendsCrcLowByteFirst) {
    std::array<std::uint8_t, 16> out{};
    const EncodeResult r = encode_rtu_frame(0x11, hex_bytes("03 00 6B 00 03"), out);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(to_vec(Bytes(out.data(), r.size)), hex_bytes("11 03 00 6B 00 03 76 87"));
}

TEST(RtuEncode, PduInPlaceAndErrors) {
    std::array<std::uint8_t, limits::kMaxRtuAdu + 1> out{};
    const ByteVec pdu = hex_bytes("03 00 6B 00 03");
    std::memcpy(out.data() + 1, pdu.data(), pdu.size());
    const EncodeResult r = encode_rtu_frame(0x11, Bytes(out.data() + 1, pdu.size()), out);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(to_vec(Bytes(out.data(), r.size)), hex_bytes("11 03 00 6B 00 03 76 87"));

    EXPECT_EQ(encode_rtu_frame(1, {}, out).error, CodecError::InvalidArgument);
    const ByteVec max(limits::kMaxPdu, 0x10);
    const ByteVec too_big(limits::kMaxPdu + 1, 0x10);
    EXPECT_EQ(encode_rtu_frame(1, too_big, out).error, CodecError::InvalidArgument);
    EXPECT_EQ(encode_rtu_frame(1, max, MutableBytes(out.data(), 255)).error,
              CodecError::BufferTooSmall);
    const EncodeResult m = encode_rtu_frame(1, max, out);
    ASSERT_TRUE(m.ok());
    EXPECT_EQ(m.size, limits::kMaxRtuAdu);
}

TEST(RtuDecode, DecodesAndRejects) {
    const ByteVec good = hex_bytes("11 03 00 6B 00 03 76 87");
    RtuFrame f;
    ASSERT_EQ(decode_rtu_frame(good, f), CodecError::Ok);
    EXPECT_EQ(f.address, 0x11);
    EXPECT_EQ(to_vec(f.pdu), hex_bytes("03 00 6B 00 03"));
    EXPECT_EQ(f.adu.size(), good.size());

    EXPECT_EQ(decode_rtu_frame({}, f), CodecError::Empty);
    EXPECT_EQ(decode_rtu_frame(Bytes(good.data(), 3), f), CodecError::Truncated);
    // CRC bytes in the wrong order (high first, as some tables print them): BadCrc.
    EXPECT_EQ(decode_rtu_frame(hex_bytes("11 03 00 6B 00 03 87 76"), f), CodecError::BadCrc);
    const ByteVec too_long(limits::kMaxRtuAdu + 1, 0);
    EXPECT_EQ(decode_rtu_frame(too_long, f), CodecError::FrameTooLong);
    // Every single-bit error is caught.
    for (std::size_t bit = 0; bit < good.size() * 8; ++bit) {
        ByteVec bad = good;
        bad[bit / 8] ^= static_cast<std::uint8_t>(1u << (bit % 8));
        EXPECT_EQ(decode_rtu_frame(bad, f), CodecError::BadCrc) << bit;
    }
}

TEST(RtuDecode, RoundTripsEverySize) {
    for (std::size_t n = 1; n <= limits::kMaxPdu; ++n) {
        ByteVec pdu(n);
        for (std::size_t i = 0; i < n; ++i) pdu[i] = static_cast<std::uint8_t>(i * 31 + n);
        std::array<std::uint8_t, limits::kMaxRtuAdu> out{};
        const EncodeResult r = encode_rtu_frame(0xF7, pdu, out);
        ASSERT_TRUE(r.ok());
        RtuFrame f;
        ASSERT_EQ(decode_rtu_frame(Bytes(out.data(), r.size), f), CodecError::Ok);
        EXPECT_EQ(f.address, 0xF7);
        EXPECT_EQ(to_vec(f.pdu), pdu);
    }
}

// Whole frames (with a dummy CRC) and their expected inferred length; every proper prefix
// must answer NeedMore with a size it can actually reach, never more than the frame.
void expect_length(RtuLength (*infer)(Bytes), const ByteVec& frame) {
    const RtuLength whole = infer(frame);
    ASSERT_EQ(whole.status, LenStatus::Known) << ::testing::PrintToString(frame);
    EXPECT_EQ(whole.size, frame.size()) << ::testing::PrintToString(frame);
    bool known = false;
    for (std::size_t k = 0; k < frame.size(); ++k) {
        const RtuLength r = infer(Bytes(frame.data(), k));
        if (r.status == LenStatus::Known) {
            known = true;
            EXPECT_EQ(r.size, frame.size());
        } else {
            ASSERT_FALSE(known) << "prefix " << k << " went back to NeedMore";
            ASSERT_EQ(r.status, LenStatus::NeedMore) << k;
            EXPECT_GT(r.size, k);
            EXPECT_LE(r.size, frame.size());
        }
    }
}

ByteVec with_crc(std::string_view body_hex) {
    ByteVec b = hex_bytes(body_hex);
    const std::uint16_t crc = crc16(b);
    b.push_back(static_cast<std::uint8_t>(crc));
    b.push_back(static_cast<std::uint8_t>(crc >> 8));
    return b;
}

TEST(RtuLength, Requests) {
    const char* requests[] = {
        "11 01 00 13 00 25",
        "11 02 00 C4 00 16",
        "11 03 00 6B 00 03",
        "11 04 00 08 00 01",
        "11 05 00 AC FF 00",
        "11 06 00 01 00 03",
        "11 07",
        "11 08 00 00 A5 37",
        "11 0B",
        "11 0C",
        "11 0F 00 13 00 0A 02 CD 01",
        "11 10 00 01 00 02 04 00 0A 01 02",
        "11 11",
        "11 14 0E 06 00 04 00 01 00 02 06 00 03 00 09 00 02",
        "11 15 0D 06 00 04 00 07 00 03 06 AF 04 BE 10 0D",
        "11 16 00 04 00 F2 00 25",
        "11 17 00 03 00 06 00 0E 00 03 06 00 FF 00 FF 00 FF",
        "11 18 04 DE",
        "11 2B 0E 01 00",
    };
    for (const char* r : requests) expect_length(rtu_request_length, with_crc(r));
}

TEST(RtuLength, Responses) {
    const char* responses[] = {
        "11 01 05 CD 6B B2 0E 1B",
        "11 02 03 AC DB 35",
        "11 03 06 02 2B 00 00 00 64",
        "11 04 02 00 0A",
        "11 05 00 AC FF 00",
        "11 06 00 01 00 03",
        "11 07 6D",
        "11 08 00 00 A5 37",
        "11 0B 00 00 01 08",
        "11 0C 08 00 00 01 08 01 21 20 00",
        "11 0F 00 13 00 0A",
        "11 10 00 01 00 02",
        "11 11 03 11 FF 00",
        "11 14 0C 05 06 0D FE 00 20 05 06 33 CD 00 40",
        "11 15 0D 06 00 04 00 07 00 03 06 AF 04 BE 10 0D",
        "11 16 00 04 00 F2 00 25",
        "11 17 0C 00 FE 0A CD 00 01 00 03 00 0D 00 FF",
        "11 18 00 06 00 02 01 B8 12 84",
        "11 2B 0E 01 01 00 00 03 00 03 41 42 43 01 02 58 59 02 00",
        "11 2B 0E 01 01 00 00 00",
        "11 83 02",
        "11 81 01",
        "11 AB 01",
        "11 FF 04",
    };
    for (const char* r : responses) expect_length(rtu_response_length, with_crc(r));
}

TEST(RtuLength, UnknownFunctions) {
    for (int fc : {0x00, 0x09, 0x0A, 0x0D, 0x0E, 0x12, 0x13, 0x19, 0x2A, 0x41, 0x64, 0x7F}) {
        const ByteVec b = {0x01, static_cast<std::uint8_t>(fc), 0, 0, 0, 0, 0, 0};
        EXPECT_EQ(rtu_request_length(b).status, LenStatus::Unknown) << fc;
        EXPECT_EQ(rtu_response_length(b).status, LenStatus::Unknown) << fc;
    }
    // MEI types other than Read Device Identification have no length rule.
    EXPECT_EQ(rtu_request_length(hex_bytes("01 2B 0D 00")).status, LenStatus::Unknown);
    EXPECT_EQ(rtu_response_length(hex_bytes("01 2B 0D 00")).status, LenStatus::Unknown);
    // Without the function code nothing is known yet.
    EXPECT_EQ(rtu_request_length({}).status, LenStatus::NeedMore);
    EXPECT_EQ(rtu_request_length(hex_bytes("01")).size, 2u);
    EXPECT_EQ(rtu_request_length(hex_bytes("01 2B")).size, 3u);
}

TEST(RtuLength, ByteCountsThatCannotFitAreTooLong) {
    // 5 + 0xFC = 257 > 256.
    EXPECT_EQ(rtu_response_length(hex_bytes("01 03 FC")).status, LenStatus::TooLong);
    EXPECT_EQ(rtu_response_length(hex_bytes("01 03 FB")).status, LenStatus::Known);
    EXPECT_EQ(rtu_response_length(hex_bytes("01 03 FB")).size, 256u);
    // FC0F/10 request: 9 + byte count.
    EXPECT_EQ(rtu_request_length(hex_bytes("01 10 00 00 00 7B F7")).size, 256u);
    EXPECT_EQ(rtu_request_length(hex_bytes("01 10 00 00 00 7B F8")).status, LenStatus::TooLong);
    // FC17 request: 13 + byte count.
    EXPECT_EQ(rtu_request_length(hex_bytes("01 17 00 00 00 01 00 00 00 79 F4")).status,
              LenStatus::TooLong);
    // FC18 response: 16-bit byte count.
    EXPECT_EQ(rtu_response_length(hex_bytes("01 18 FF FF")).status, LenStatus::TooLong);
    // FC2B/0E objects adding up past 256 bytes.
    ByteVec dev = hex_bytes("01 2B 0E 01 01 00 00 03 00 F0");
    dev.resize(dev.size() + 0xF0, 'x');
    dev.push_back(0x01);
    dev.push_back(0x20);
    EXPECT_EQ(rtu_response_length(dev).status, LenStatus::TooLong);
}

}  // namespace
}  // namespace mbstorm::codec
