// RtuSplitter: RTU frames cut out of a TCP byte stream (RTU over TCP), and the helpers that
// turn MBAP requests and exceptions into RTU frames.
#include <gtest/gtest.h>

#include <vector>

#include "codec/rtu.hpp"
#include "codec/rtu_stream.hpp"

namespace mbstorm::codec {
namespace {

using Bytes8 = std::vector<std::uint8_t>;

Bytes8 rtu_frame_with_crc(Bytes8 frame) {
    const std::uint16_t crc = crc16(Bytes(frame.data(), frame.size()));
    frame.push_back(static_cast<std::uint8_t>(crc & 0xFF));
    frame.push_back(static_cast<std::uint8_t>(crc >> 8));
    return frame;
}

// Feeds `stream` in pieces of `piece` bytes; collects the frames (as ADU bytes) until Fatal.
struct Cut {
    std::vector<Bytes8> frames;
    bool fatal = false;
    CodecError error = CodecError::Ok;
};
Cut cut(RtuSplitter& s, const Bytes8& stream, std::size_t piece) {
    Cut out;
    for (std::size_t at = 0; at < stream.size() && !out.fatal; at += piece) {
        s.feed(Bytes(stream.data() + at, std::min(piece, stream.size() - at)));
        TcpFrame f;
        for (;;) {
            const auto st = s.next(f);
            if (st == RtuSplitter::Status::NeedMore) break;
            if (st == RtuSplitter::Status::Fatal) {
                out.fatal = true;
                out.error = s.error();
                break;
            }
            out.frames.emplace_back(f.adu.begin(), f.adu.end());
            EXPECT_EQ(f.header.unit_id, f.adu[0]);
            EXPECT_EQ(f.pdu.size() + 3, f.adu.size());
        }
    }
    return out;
}

TEST(RtuSplitter, CutsPipelinedRequestsWhateverTheSegmentSizes) {
    const Bytes8 read = rtu_frame_with_crc({0x11, 0x03, 0x00, 0x6B, 0x00, 0x03});
    const Bytes8 write =
        rtu_frame_with_crc({0x11, 0x10, 0x00, 0x01, 0x00, 0x02, 0x04, 0x00, 0x0A, 0x01, 0x02});
    const Bytes8 status = rtu_frame_with_crc({0x01, 0x07});
    Bytes8 stream;
    for (const Bytes8* f : {&read, &write, &status, &read})
        stream.insert(stream.end(), f->begin(), f->end());
    for (std::size_t piece : {1u, 2u, 3u, 5u, 7u, 64u}) {
        RtuSplitter s;
        const Cut c = cut(s, stream, piece);
        ASSERT_FALSE(c.fatal) << "piece " << piece;
        ASSERT_EQ(c.frames.size(), 4u) << "piece " << piece;
        EXPECT_EQ(c.frames[0], read);
        EXPECT_EQ(c.frames[1], write);
        EXPECT_EQ(c.frames[2], status);
        EXPECT_EQ(c.frames[3], read);
        EXPECT_EQ(s.buffered(), 0u);
    }
}

TEST(RtuSplitter, CutsResponsesIncludingExceptions) {
    const Bytes8 regs = rtu_frame_with_crc({0x11, 0x03, 0x06, 0x02, 0x2B, 0x00, 0x00, 0x00, 0x64});
    const Bytes8 exc = rtu_frame_with_crc({0x11, 0x83, 0x02});
    Bytes8 stream = regs;
    stream.insert(stream.end(), exc.begin(), exc.end());
    for (std::size_t piece : {1u, 4u, 100u}) {
        RtuSplitter s(RtuSplitter::Direction::Responses);
        const Cut c = cut(s, stream, piece);
        ASSERT_FALSE(c.fatal);
        ASSERT_EQ(c.frames.size(), 2u);
        EXPECT_EQ(c.frames[0], regs);
        EXPECT_EQ(c.frames[1], exc);
    }
}

TEST(RtuSplitter, BadCrcIsFatalAfterTheGoodFramesBeforeIt) {
    const Bytes8 good = rtu_frame_with_crc({0x01, 0x03, 0x00, 0x00, 0x00, 0x01});
    Bytes8 bad = good;
    bad.back() ^= 0x01;
    Bytes8 stream = good;
    stream.insert(stream.end(), bad.begin(), bad.end());
    stream.insert(stream.end(), good.begin(), good.end());
    for (std::size_t piece : {1u, 3u, 100u}) {
        RtuSplitter s;
        const Cut c = cut(s, stream, piece);
        EXPECT_TRUE(c.fatal);
        EXPECT_EQ(c.error, CodecError::BadCrc);
        ASSERT_EQ(c.frames.size(), 1u);
        // Fatal stays fatal until reset.
        TcpFrame f;
        s.feed(Bytes(good.data(), good.size()));
        EXPECT_EQ(s.next(f), RtuSplitter::Status::Fatal);
        s.reset();
        s.feed(Bytes(good.data(), good.size()));
        EXPECT_EQ(s.next(f), RtuSplitter::Status::Frame);
    }
}

TEST(RtuSplitter, ByteCountPastTheRtuLimitIsFatal) {
    // FC16 announcing 250 data bytes: 7 + 250 + 2 > 256.
    const Bytes8 head = {0x01, 0x10, 0x00, 0x00, 0x00, 0x7D, 0xFA};
    RtuSplitter s;
    const Cut c = cut(s, head, 100);
    EXPECT_TRUE(c.fatal);
    EXPECT_EQ(c.error, CodecError::FrameTooLong);
}

TEST(RtuSplitter, UnknownFunctionEndsWhereItsCrcHolds) {
    const Bytes8 odd = rtu_frame_with_crc({0x01, 0x41, 0x12, 0x34});
    RtuSplitter s;
    Cut c = cut(s, odd, odd.size());
    ASSERT_FALSE(c.fatal);
    ASSERT_EQ(c.frames.size(), 1u);
    EXPECT_EQ(c.frames[0], odd);
    // Arriving byte by byte, it completes once the bytes so far end in a valid CRC.
    RtuSplitter t;
    c = cut(t, odd, 1);
    ASSERT_EQ(c.frames.size(), 1u);
    EXPECT_EQ(c.frames[0], odd);
}

TEST(RtuSplitter, UnknownFunctionFollowedByAnotherFrameInOneChunkIsTwoFrames) {
    const Bytes8 odd = rtu_frame_with_crc({0x01, 0x41, 0x12, 0x34, 0x56});
    const Bytes8 read = rtu_frame_with_crc({0x01, 0x03, 0x00, 0x00, 0x00, 0x01});
    Bytes8 stream = odd;
    stream.insert(stream.end(), read.begin(), read.end());
    for (std::size_t piece : {1u, 6u, 100u}) {
        RtuSplitter s;
        const Cut c = cut(s, stream, piece);
        ASSERT_FALSE(c.fatal) << "piece " << piece;
        ASSERT_EQ(c.frames.size(), 2u) << "piece " << piece;
        EXPECT_EQ(c.frames[0], odd);
        EXPECT_EQ(c.frames[1], read);
    }
}

TEST(RtuSplitter, UnknownFunctionWithoutValidCrcFailsAtTheRtuLimit) {
    Bytes8 junk(300, 0x00);
    junk[0] = 0x01;
    junk[1] = 0x41;
    RtuSplitter s;
    const Cut c = cut(s, junk, 50);
    EXPECT_TRUE(c.fatal);
    EXPECT_TRUE(c.frames.empty());
}

TEST(RtuStream, MbapRequestBecomesRtuInPlace) {
    std::uint8_t adu[] = {0x12, 0x34, 0x00, 0x00, 0x00, 0x06, 0x11, 0x03, 0x00, 0x6B, 0x00, 0x03};
    const std::size_t n = mbap_to_rtu_in_place(adu, sizeof adu);
    ASSERT_EQ(n, 8u);
    // The classic example frame from the Modbus serial line guide: 11 03 006B 0003 CRC 7687.
    EXPECT_EQ(Bytes8(adu, adu + n), (Bytes8{0x11, 0x03, 0x00, 0x6B, 0x00, 0x03, 0x76, 0x87}));
    EXPECT_EQ(mbap_to_rtu_in_place(adu, 6), 0u);
}

TEST(RtuStream, ExceptionFrame) {
    std::uint8_t out[kRtuExceptionAduSize];
    write_rtu_exception(out, 0x0A, 0x01, 0x02);
    RtuFrame f;
    ASSERT_EQ(decode_rtu_frame(Bytes(out, sizeof out), f), CodecError::Ok);
    EXPECT_EQ(f.address, 0x0A);
    EXPECT_EQ(Bytes8(f.pdu.begin(), f.pdu.end()), (Bytes8{0x81, 0x02}));
}

}  // namespace
}  // namespace mbstorm::codec
