// SerialFrameReader: where RTU and ASCII frames end on a serial line, and what is dropped.
#include <gtest/gtest.h>

#include <array>
#include <string>
#include <vector>

#include "codec/ascii.hpp"
#include "codec/rtu.hpp"
#include "codec/serial_frame_reader.hpp"

namespace mbstorm::codec {
namespace {

using Kind = SerialFrameReader::Result::Kind;
using Reads = SerialFrameReader::Reads;

std::vector<std::uint8_t> rtu(std::uint8_t unit, std::vector<std::uint8_t> pdu) {
    std::vector<std::uint8_t> out(pdu.size() + 3);
    auto r = encode_rtu_frame(unit, pdu, out);
    EXPECT_TRUE(r.ok());
    out.resize(r.size);
    return out;
}

std::string ascii(std::uint8_t unit, std::vector<std::uint8_t> pdu) {
    std::string out(ascii_frame_size(pdu.size()), '\0');
    auto r = encode_ascii_frame(
        unit, pdu, MutableBytes(reinterpret_cast<std::uint8_t*>(out.data()), out.size()));
    EXPECT_TRUE(r.ok());
    return out;
}

Bytes bytes(const std::string& s) {
    return Bytes(reinterpret_cast<const std::uint8_t*>(s.data()), s.size());
}

const std::vector<std::uint8_t> kRead{0x03, 0x00, 0x10, 0x00, 0x02};  // FC03 at 16, 2 regs

TEST(SerialFrameReader, RtuRequestEndsWhenItsLengthIsKnownWithoutWaitingForSilence) {
    SerialFrameReader r(Framing::Rtu, Reads::Requests);
    auto frame_bytes = rtu(7, kRead);
    r.feed(Bytes(frame_bytes.data(), 3));
    SerialFrame f;
    EXPECT_EQ(r.next(f).kind, Kind::None);
    r.feed(Bytes(frame_bytes.data() + 3, frame_bytes.size() - 3));
    ASSERT_EQ(r.next(f).kind, Kind::Frame);
    EXPECT_EQ(f.address, 7);
    EXPECT_EQ(std::vector<std::uint8_t>(f.pdu.begin(), f.pdu.end()), kRead);
    EXPECT_FALSE(r.pending());
}

TEST(SerialFrameReader, RtuBackToBackFramesAreSplitByLength) {
    SerialFrameReader r(Framing::Rtu, Reads::Requests);
    auto a = rtu(1, kRead);
    auto b = rtu(2, {0x06, 0x00, 0x01, 0x12, 0x34});
    a.insert(a.end(), b.begin(), b.end());
    r.feed(a);
    SerialFrame f;
    ASSERT_EQ(r.next(f).kind, Kind::Frame);
    EXPECT_EQ(f.address, 1);
    ASSERT_EQ(r.next(f).kind, Kind::Frame);
    EXPECT_EQ(f.address, 2);
    EXPECT_EQ(r.next(f).kind, Kind::None);
}

TEST(SerialFrameReader, RtuBadCrcIsReportedAndTheRestOfTheBurstDroppedUntilSilence) {
    SerialFrameReader r(Framing::Rtu, Reads::Requests);
    auto a = rtu(1, kRead);
    a.back() ^= 0xFF;
    r.feed(a);
    SerialFrame f;
    auto res = r.next(f);
    ASSERT_EQ(res.kind, Kind::Error);
    EXPECT_EQ(res.error, CodecError::BadCrc);
    EXPECT_EQ(res.dropped, a.size());
    // More bytes of the same burst: part of the broken transmission.
    auto good = rtu(1, kRead);
    r.feed(good);
    EXPECT_EQ(r.next(f).kind, Kind::None);
    EXPECT_TRUE(r.pending());
    EXPECT_EQ(r.next(f, /*silent=*/true).kind, Kind::None);  // already reported
    EXPECT_FALSE(r.pending());
    // After the silence the line is in sync again.
    r.feed(good);
    EXPECT_EQ(r.next(f).kind, Kind::Frame);
}

TEST(SerialFrameReader, RtuFrameCutShortBySilenceIsTruncated) {
    SerialFrameReader r(Framing::Rtu, Reads::Requests);
    auto a = rtu(1, kRead);
    r.feed(Bytes(a.data(), 5));
    SerialFrame f;
    EXPECT_EQ(r.next(f).kind, Kind::None);
    auto res = r.next(f, true);
    ASSERT_EQ(res.kind, Kind::Error);
    EXPECT_EQ(res.error, CodecError::Truncated);
    EXPECT_EQ(res.dropped, 5u);
    EXPECT_FALSE(r.pending());
}

TEST(SerialFrameReader, RtuGapLongerThanOneAndAHalfCharactersBreaksTheFrame) {
    SerialFrameReader r(Framing::Rtu, Reads::Requests);
    auto a = rtu(1, kRead);
    r.feed(Bytes(a.data(), 4));
    SerialFrame f;
    EXPECT_EQ(r.next(f).kind, Kind::None);
    r.feed(Bytes(a.data() + 4, a.size() - 4), /*after_gap=*/true);
    EXPECT_EQ(r.next(f).kind, Kind::None);  // not a frame, even though the bytes add up
    auto res = r.next(f, true);
    ASSERT_EQ(res.kind, Kind::Error);
    EXPECT_EQ(res.error, CodecError::Truncated);
    EXPECT_EQ(res.dropped, a.size());
}

TEST(SerialFrameReader, RtuUnknownFunctionEndsAtTheSilence) {
    SerialFrameReader r(Framing::Rtu, Reads::Requests);
    auto a = rtu(3, {0x41, 0x01, 0x02, 0x03});  // a user-defined function code
    r.feed(a);
    SerialFrame f;
    EXPECT_EQ(r.next(f).kind, Kind::None);
    ASSERT_EQ(r.next(f, true).kind, Kind::Frame);
    EXPECT_EQ(f.pdu.size(), 4u);
    EXPECT_EQ(f.pdu[0], 0x41);
}

TEST(SerialFrameReader, RtuResponsesUseTheResponseLengthRules) {
    SerialFrameReader r(Framing::Rtu, Reads::Responses);
    auto a = rtu(1, {0x03, 0x04, 0x00, 0x01, 0x00, 0x02});
    auto e = rtu(1, {0x83, 0x02});
    a.insert(a.end(), e.begin(), e.end());
    r.feed(a);
    SerialFrame f;
    ASSERT_EQ(r.next(f).kind, Kind::Frame);
    EXPECT_EQ(f.pdu.size(), 6u);
    ASSERT_EQ(r.next(f).kind, Kind::Frame);
    EXPECT_EQ(f.pdu[0], 0x83);
}

TEST(SerialFrameReader, RtuEndlessStreamIsDroppedAsTooLong) {
    SerialFrameReader r(Framing::Rtu, Reads::Requests);
    std::vector<std::uint8_t> noise(2000, 0x41);  // unit 0x41, FC 0x41: no length rule
    r.feed(noise);
    SerialFrame f;
    EXPECT_EQ(r.next(f).kind, Kind::None);
    auto res = r.next(f, true);
    ASSERT_EQ(res.kind, Kind::Error);
    EXPECT_EQ(res.error, CodecError::FrameTooLong);
    EXPECT_EQ(res.dropped, 2000u);
}

TEST(SerialFrameReader, AsciiFrameEndsAtLineFeed) {
    SerialFrameReader r(Framing::Ascii, Reads::Requests);
    const std::string text = ascii(0x11, kRead);
    r.feed(bytes(text.substr(0, 6)));
    SerialFrame f;
    EXPECT_EQ(r.next(f).kind, Kind::None);
    r.feed(bytes(text.substr(6)));
    ASSERT_EQ(r.next(f).kind, Kind::Frame);
    EXPECT_EQ(f.address, 0x11);
    EXPECT_EQ(std::vector<std::uint8_t>(f.pdu.begin(), f.pdu.end()), kRead);
    EXPECT_EQ(f.adu.size(), text.size());
}

TEST(SerialFrameReader, AsciiNoiseBeforeTheColonIsDroppedAndReported) {
    SerialFrameReader r(Framing::Ascii, Reads::Requests);
    r.feed(bytes("xyz" + ascii(1, kRead)));
    SerialFrame f;
    auto res = r.next(f);
    ASSERT_EQ(res.kind, Kind::Error);
    EXPECT_EQ(res.error, CodecError::MissingStart);
    EXPECT_EQ(res.dropped, 3u);
    EXPECT_EQ(r.next(f).kind, Kind::Frame);
}

TEST(SerialFrameReader, AsciiNewColonRestartsAndBadLrcIsReported) {
    SerialFrameReader r(Framing::Ascii, Reads::Requests);
    std::string bad = ascii(1, kRead);
    bad[bad.size() - 3] = bad[bad.size() - 3] == '0' ? '1' : '0';  // LRC's low digit
    r.feed(bytes(":0103" + bad + ascii(2, kRead)));
    SerialFrame f;
    auto res = r.next(f);
    ASSERT_EQ(res.kind, Kind::Error);
    EXPECT_EQ(res.error, CodecError::MissingEnd);
    res = r.next(f);
    ASSERT_EQ(res.kind, Kind::Error);
    EXPECT_EQ(res.error, CodecError::BadLrc);
    ASSERT_EQ(r.next(f).kind, Kind::Frame);
    EXPECT_EQ(f.address, 2);
}

TEST(SerialFrameReader, AsciiOpenFrameIsTruncatedAtTheTimeout) {
    SerialFrameReader r(Framing::Ascii, Reads::Responses);
    r.feed(bytes(":010302"));
    SerialFrame f;
    EXPECT_EQ(r.next(f).kind, Kind::None);
    auto res = r.next(f, true);
    ASSERT_EQ(res.kind, Kind::Error);
    EXPECT_EQ(res.error, CodecError::Truncated);
}

}  // namespace
}  // namespace mbstorm::codec
