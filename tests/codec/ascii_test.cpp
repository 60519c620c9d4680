// Modbus ASCII framing and LRC.
#include <gtest/gtest.h>

#include <array>
#include <string>

#include "codec/ascii.hpp"
#include "framing_test_support.hpp"

namespace mbstorm::codec {
namespace {

using framing_test::ByteVec;
using framing_test::hex_bytes;
using framing_test::to_vec;

std::string as_text(const std::array<std::uint8_t, limits::kMaxAsciiAdu>& buf, std::size_t n) {
    return std::string(reinterpret_cast<const char*>(buf.data()), n);
}

TEST(Lrc, TwosComplementOfTheSum) {
    // Serial line guide example: 11 03 00 6B 00 03 sums to 0x82, LRC 0x7E.
    EXPECT_EQ(lrc(hex_bytes("11 03 00 6B 00 03")), 0x7E);
    EXPECT_EQ(lrc({}), 0x00);
    EXPECT_EQ(lrc(hex_bytes("01")), 0xFF);
    EXPECT_EQ(lrc(hex_bytes("FF FF")), 0x02);  // sum wraps at 8 bits
}

TEST(AsciiEncode, ProducesUppercaseHexWithColonAndCrLf) {
    std::array<std::uint8_t, limits::kMaxAsciiAdu> out{};
    const EncodeResult r = encode_ascii_frame(0x11, hex_bytes("03 00 6B 00 03"), out);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(as_text(out, r.size), ":1103006B00037E\r\n");
    EXPECT_EQ(r.size, ascii_frame_size(5));
}

TEST(AsciiEncode, Limits) {
    std::array<std::uint8_t, limits::kMaxAsciiAdu> out{};
    EXPECT_EQ(encode_ascii_frame(1, {}, out).error, CodecError::InvalidArgument);
    const ByteVec max(limits::kMaxPdu, 0xAB);
    const EncodeResult r = encode_ascii_frame(1, max, out);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r.size, limits::kMaxAsciiAdu);
    const ByteVec too_big(limits::kMaxPdu + 1, 0xAB);
    EXPECT_EQ(encode_ascii_frame(1, too_big, out).error, CodecError::InvalidArgument);
    EXPECT_EQ(encode_ascii_frame(1, max, MutableBytes(out.data(), out.size() - 1)).error,
              CodecError::BufferTooSmall);
}

TEST(AsciiDecode, DecodesIntoCallerBuffer) {
    std::array<std::uint8_t, 8> buf{};
    AsciiFrame f;
    ASSERT_EQ(decode_ascii_frame(":1103006B00037E\r\n", buf, f), CodecError::Ok);
    EXPECT_EQ(f.address, 0x11);
    EXPECT_EQ(to_vec(f.pdu), hex_bytes("03 00 6B 00 03"));
    EXPECT_EQ(f.binary.size(), 7u);
    EXPECT_EQ(f.binary.data(), buf.data());
    // Lower case digits are accepted too.
    ASSERT_EQ(decode_ascii_frame(":1103006b00037e\r\n", buf, f), CodecError::Ok);
    EXPECT_EQ(to_vec(f.pdu), hex_bytes("03 00 6B 00 03"));
}

TEST(AsciiDecode, EveryError) {
    std::array<std::uint8_t, 300> buf{};
    AsciiFrame f;
    EXPECT_EQ(decode_ascii_frame("", buf, f), CodecError::Empty);
    EXPECT_EQ(decode_ascii_frame("1103006B00037E\r\n", buf, f), CodecError::MissingStart);
    EXPECT_EQ(decode_ascii_frame(":1103006B00037E", buf, f), CodecError::MissingEnd);
    EXPECT_EQ(decode_ascii_frame(":1103006B00037E\n", buf, f), CodecError::MissingEnd);
    EXPECT_EQ(decode_ascii_frame(":1103006B00037E\n\r", buf, f), CodecError::MissingEnd);
    EXPECT_EQ(decode_ascii_frame(":", buf, f), CodecError::MissingEnd);
    EXPECT_EQ(decode_ascii_frame(":\r", buf, f), CodecError::MissingEnd);
    EXPECT_EQ(decode_ascii_frame(":1103006B00037\r\n", buf, f), CodecError::OddHexLength);
    EXPECT_EQ(decode_ascii_frame(":1103006G00037E\r\n", buf, f), CodecError::BadHexDigit);
    EXPECT_EQ(decode_ascii_frame(":11 03006B00037\r\n", buf, f), CodecError::BadHexDigit);
    EXPECT_EQ(decode_ascii_frame(":1103006B00037F\r\n", buf, f), CodecError::BadLrc);
    EXPECT_EQ(decode_ascii_frame(":\r\n", buf, f), CodecError::Truncated);
    EXPECT_EQ(decode_ascii_frame(":01FF\r\n", buf, f), CodecError::Truncated);
    EXPECT_EQ(decode_ascii_frame(":1103006B00037E\r\n", MutableBytes(buf.data(), 6), f),
              CodecError::BufferTooSmall);
    std::string too_long = ":" + std::string(limits::kMaxAsciiAdu - 2, '0') + "\r\n";
    EXPECT_EQ(decode_ascii_frame(too_long, buf, f), CodecError::FrameTooLong);
}

TEST(AsciiDecode, RoundTripsEverySize) {
    for (std::size_t n = 1; n <= limits::kMaxPdu; ++n) {
        ByteVec pdu(n);
        for (std::size_t i = 0; i < n; ++i) pdu[i] = static_cast<std::uint8_t>(i * 13 + n);
        std::array<std::uint8_t, limits::kMaxAsciiAdu> text{};
        const EncodeResult r = encode_ascii_frame(0x2A, pdu, text);
        ASSERT_TRUE(r.ok());
        std::array<std::uint8_t, 256> bin{};
        AsciiFrame f;
        ASSERT_EQ(decode_ascii_frame(Bytes(text.data(), r.size), bin, f), CodecError::Ok);
        EXPECT_EQ(f.address, 0x2A);
        EXPECT_EQ(to_vec(f.pdu), pdu);
    }
}

}  // namespace
}  // namespace mbstorm::codec
