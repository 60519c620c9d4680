// The in-place MBAP writers the server's hot path uses.
#include <gtest/gtest.h>

#include <array>
#include <vector>

#include "codec/mbap.hpp"

namespace mbstorm::codec {
namespace {

TEST(MbapWriter, HeaderInFrontOfAnInPlacePduDecodesAsTheSameFrame) {
    std::array<std::uint8_t, limits::kMaxTcpAdu> adu{};
    const std::uint8_t pdu[] = {0x03, 0x00, 0x10, 0x00, 0x02};
    std::copy(std::begin(pdu), std::end(pdu), adu.begin() + limits::kMbapHeader);
    write_mbap_header(adu.data(), 0xBEEF, 0x11, sizeof pdu);
    TcpFrame frame;
    ASSERT_EQ(decode_tcp_frame(Bytes(adu.data(), limits::kMbapHeader + sizeof pdu), frame),
              CodecError::Ok);
    EXPECT_EQ(frame.header.transaction_id, 0xBEEF);
    EXPECT_EQ(frame.header.protocol_id, 0);
    EXPECT_EQ(frame.header.unit_id, 0x11);
    EXPECT_EQ(std::vector<std::uint8_t>(frame.pdu.begin(), frame.pdu.end()),
              std::vector<std::uint8_t>(std::begin(pdu), std::end(pdu)));
}

TEST(MbapWriter, ExceptionFrameAnswersTheRequestsTransactionUnitAndFunction) {
    const std::uint8_t request_adu[] = {0x12, 0x34, 0, 0, 0, 6, 0x07, 0x10, 0, 1, 0, 2};
    TcpFrame request;
    ASSERT_EQ(decode_tcp_frame(request_adu, request), CodecError::Ok);
    std::array<std::uint8_t, kExceptionAduSize> out{};
    write_exception_frame(out.data(), request, ExceptionCode::ServerDeviceBusy);
    EXPECT_EQ(out, (std::array<std::uint8_t, 9>{0x12, 0x34, 0, 0, 0, 3, 0x07, 0x90, 0x06}));

    TcpFrame empty = request;
    empty.pdu = {};
    write_exception_frame(out.data(), empty, ExceptionCode::GatewayTargetFailedToRespond);
    EXPECT_EQ(out[7], 0x80);
    EXPECT_EQ(out[8], 0x0B);
}

TEST(MbapWriter, RawFrameKeepsALyingLengthAndProtocolId) {
    std::array<std::uint8_t, 16> out{};
    const std::uint8_t pdu[] = {0x03, 0x00, 0x00, 0x00, 0x01};
    const EncodeResult r = encode_raw_tcp_frame({0x0102, 0x0007, 0x0020, 0x09}, pdu, out);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r.size, 12u);
    EXPECT_EQ(std::vector<std::uint8_t>(out.begin(), out.begin() + 12),
              (std::vector<std::uint8_t>{1, 2, 0, 7, 0, 0x20, 9, 3, 0, 0, 0, 1}));
    const MbapHeader h = read_mbap_header(out.data());
    EXPECT_EQ(h.length, 0x20);
    EXPECT_EQ(check_mbap_header(h), CodecError::BadProtocolId);
    // A header alone, and a buffer too small for the PDU.
    EXPECT_EQ(encode_raw_tcp_frame({1, 0, 6, 1}, {}, out).size, 7u);
    std::array<std::uint8_t, 8> small{};
    EXPECT_EQ(encode_raw_tcp_frame({1, 0, 6, 1}, pdu, small).error, CodecError::BufferTooSmall);
}

}  // namespace
}  // namespace mbstorm::codec
