// MBAP header helpers, single-frame decode and encode.
#include <gtest/gtest.h>

#include <array>
#include <cstring>

#include "codec/mbap.hpp"
#include "framing_test_support.hpp"

namespace mbstorm::codec {
namespace {

using framing_test::ByteVec;
using framing_test::hex_bytes;
using framing_test::to_vec;

TEST(MbapHeader, ReadsBigEndianFields) {
    const ByteVec b = hex_bytes("97 76 00 00 00 06 04");
    const MbapHeader h = read_mbap_header(b.data());
    EXPECT_EQ(h.transaction_id, 0x9776);
    EXPECT_EQ(h.protocol_id, 0);
    EXPECT_EQ(h.length, 6);
    EXPECT_EQ(h.unit_id, 4);
}

TEST(MbapHeader, ChecksEachField) {
    EXPECT_EQ(check_mbap_header({1, 0, 2, 1}), CodecError::Ok);
    EXPECT_EQ(check_mbap_header({1, 0, 254, 1}), CodecError::Ok);
    EXPECT_EQ(check_mbap_header({1, 1, 6, 1}), CodecError::BadProtocolId);
    EXPECT_EQ(check_mbap_header({1, 0xFFFF, 6, 1}), CodecError::BadProtocolId);
    EXPECT_EQ(check_mbap_header({1, 0, 0, 1}), CodecError::LengthZero);
    EXPECT_EQ(check_mbap_header({1, 0, 1, 1}), CodecError::LengthOne);
    EXPECT_EQ(check_mbap_header({1, 0, 255, 1}), CodecError::LengthTooLong);
    EXPECT_EQ(check_mbap_header({1, 0, 0xFFFF, 1}), CodecError::LengthTooLong);
    // A length error wins over a bad protocol id: it is the one that breaks the stream.
    EXPECT_EQ(check_mbap_header({1, 7, 0, 1}), CodecError::LengthZero);
    EXPECT_EQ(check_mbap_header({1, 7, 300, 1}), CodecError::LengthTooLong);
}

TEST(MbapDecode, DecodesOneFrame) {
    const ByteVec a = hex_bytes("00 01 00 00 00 06 01 03 00 00 00 03");
    TcpFrame f;
    ASSERT_EQ(decode_tcp_frame(a, f), CodecError::Ok);
    EXPECT_EQ(f.header.transaction_id, 1);
    EXPECT_EQ(f.header.unit_id, 1);
    EXPECT_EQ(to_vec(f.pdu), hex_bytes("03 00 00 00 03"));
    EXPECT_EQ(f.adu.data(), a.data());
    EXPECT_EQ(f.adu.size(), a.size());
}

TEST(MbapDecode, SizeErrors) {
    const ByteVec a = hex_bytes("00 01 00 00 00 06 01 03 00 00 00 03");
    TcpFrame f;
    EXPECT_EQ(decode_tcp_frame({}, f), CodecError::Empty);
    EXPECT_EQ(decode_tcp_frame(Bytes(a.data(), 6), f), CodecError::Truncated);
    EXPECT_EQ(decode_tcp_frame(Bytes(a.data(), 7), f), CodecError::LengthMismatch);
    EXPECT_EQ(decode_tcp_frame(Bytes(a.data(), 11), f), CodecError::LengthMismatch);
    ByteVec longer = a;
    longer.push_back(0);
    EXPECT_EQ(decode_tcp_frame(longer, f), CodecError::LengthMismatch);
}

TEST(MbapDecode, HeaderErrors) {
    TcpFrame f;
    EXPECT_EQ(decode_tcp_frame(hex_bytes("00 01 00 00 00 00 01"), f), CodecError::LengthZero);
    EXPECT_EQ(decode_tcp_frame(hex_bytes("00 01 00 00 00 01 01"), f), CodecError::LengthOne);
    EXPECT_EQ(decode_tcp_frame(hex_bytes("00 01 00 00 00 FF 01 03"), f), CodecError::LengthTooLong);
    // A bad protocol id still yields the frame, so a server can skip it.
    const ByteVec a = hex_bytes("00 01 00 01 00 02 01 07");
    ASSERT_EQ(decode_tcp_frame(a, f), CodecError::BadProtocolId);
    EXPECT_EQ(f.header.protocol_id, 1);
    EXPECT_EQ(to_vec(f.pdu), ByteVec{0x07});
}

TEST(MbapEncode, WritesHeaderAndPdu) {
    const ByteVec pdu = hex_bytes("03 00 6B 00 03");
    std::array<std::uint8_t, 32> out{};
    const EncodeResult r = encode_tcp_frame(0x1234, 0x11, pdu, out);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r.size, 12u);
    EXPECT_EQ(to_vec(Bytes(out.data(), r.size)), hex_bytes("12 34 00 00 00 06 11 03 00 6B 00 03"));
}

TEST(MbapEncode, PduAlreadyInPlace) {
    std::array<std::uint8_t, 16> out{};
    const ByteVec pdu = hex_bytes("06 00 01 00 03");
    std::memcpy(out.data() + 7, pdu.data(), pdu.size());
    const EncodeResult r = encode_tcp_frame(7, 1, Bytes(out.data() + 7, pdu.size()), out);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(to_vec(Bytes(out.data(), r.size)), hex_bytes("00 07 00 00 00 06 01 06 00 01 00 03"));
}

TEST(MbapEncode, OverlappingPduIsMoved) {
    // PDU built at the front of the buffer, where the header goes: memmove semantics.
    std::array<std::uint8_t, 16> out{};
    const ByteVec pdu = hex_bytes("10 00 01 00 02 04 00 0A");
    std::memcpy(out.data() + 2, pdu.data(), pdu.size());
    const EncodeResult r = encode_tcp_frame(1, 1, Bytes(out.data() + 2, pdu.size()), out);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(to_vec(Bytes(out.data() + 7, pdu.size())), pdu);
}

TEST(MbapEncode, Errors) {
    std::array<std::uint8_t, limits::kMaxTcpAdu + 1> out{};
    const ByteVec pdu(limits::kMaxPdu, 0x03);
    EXPECT_EQ(encode_tcp_frame(1, 1, {}, out).error, CodecError::InvalidArgument);
    const ByteVec too_big(limits::kMaxPdu + 1, 0x03);
    EXPECT_EQ(encode_tcp_frame(1, 1, too_big, out).error, CodecError::InvalidArgument);
    EXPECT_EQ(encode_tcp_frame(1, 1, pdu, MutableBytes(out.data(), limits::kMaxTcpAdu - 1)).error,
              CodecError::BufferTooSmall);
    const EncodeResult r = encode_tcp_frame(1, 1, pdu, out);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r.size, limits::kMaxTcpAdu);
    EXPECT_EQ(read_mbap_header(out.data()).length, limits::kMaxMbapLength);
}

TEST(MbapEncode, RoundTripsThroughDecode) {
    for (std::size_t n = 1; n <= limits::kMaxPdu; ++n) {
        ByteVec pdu(n);
        for (std::size_t i = 0; i < n; ++i) pdu[i] = static_cast<std::uint8_t>(i + n);
        std::array<std::uint8_t, limits::kMaxTcpAdu> out{};
        const EncodeResult r = encode_tcp_frame(static_cast<std::uint16_t>(n), 9, pdu, out);
        ASSERT_TRUE(r.ok());
        TcpFrame f;
        ASSERT_EQ(decode_tcp_frame(Bytes(out.data(), r.size), f), CodecError::Ok);
        EXPECT_EQ(f.header.transaction_id, n);
        EXPECT_EQ(f.header.unit_id, 9);
        EXPECT_EQ(to_vec(f.pdu), pdu);
    }
}

}  // namespace
}  // namespace mbstorm::codec
