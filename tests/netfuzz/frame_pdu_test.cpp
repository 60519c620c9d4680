// netfuzz::frame_pdu in each framing: the bytes the codec's decoders accept (MBAP, RTU, ASCII),
// and any PDU size framed as given (a mutation may have made it one the encoder refuses).
#include <gtest/gtest.h>

#include <array>
#include <string_view>
#include <vector>

#include "codec/ascii.hpp"
#include "codec/mbap.hpp"
#include "codec/rtu.hpp"
#include "netfuzz/case.hpp"

namespace mbstorm::netfuzz {
namespace {

const std::vector<std::uint8_t> kRead = {0x03, 0x00, 0x6B, 0x00, 0x03};

TEST(FramePdu, MbapIsTheDefault) {
    const auto f = frame_pdu(kRead, 0x1234, 0x11);
    ASSERT_EQ(f.size(), 12u);
    const codec::MbapHeader h = codec::read_mbap_header(f.data());
    EXPECT_EQ(h.transaction_id, 0x1234);
    EXPECT_EQ(h.length, 6);
    EXPECT_EQ(h.unit_id, 0x11);
}

TEST(FramePdu, RtuFrameDecodes) {
    const auto f = frame_pdu(kRead, 0x1234, 0x11, codec::Framing::Rtu);
    EXPECT_EQ(f, (std::vector<std::uint8_t>{0x11, 0x03, 0x00, 0x6B, 0x00, 0x03, 0x76, 0x87}));
    // Oversized for the codec's encoder, framed anyway with a valid CRC.
    const std::vector<std::uint8_t> big(300, 0x10);
    const auto g = frame_pdu(big, 0, 1, codec::Framing::Rtu);
    ASSERT_EQ(g.size(), 303u);
    const std::uint16_t crc = codec::crc16(codec::Bytes(g.data(), 301));
    EXPECT_EQ(g[301], crc & 0xFF);
    EXPECT_EQ(g[302], crc >> 8);
}

TEST(FramePdu, AsciiFrameDecodes) {
    const auto f = frame_pdu(kRead, 0x1234, 0x11, codec::Framing::Ascii);
    const std::string_view text(reinterpret_cast<const char*>(f.data()), f.size());
    EXPECT_EQ(text, ":1103006B00037E\r\n");
    std::array<std::uint8_t, 64> buf{};
    codec::AsciiFrame out;
    EXPECT_EQ(codec::decode_ascii_frame(text, buf, out), codec::CodecError::Ok);
}

}  // namespace
}  // namespace mbstorm::netfuzz
