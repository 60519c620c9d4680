// MbapSplitter: frames must come out identical however the stream is chopped into chunks.
#include <gtest/gtest.h>

#include <cstdint>
#include <initializer_list>
#include <vector>

#include "codec/mbap.hpp"

namespace mbstorm::codec {
namespace {

using ByteVec = std::vector<std::uint8_t>;
using Status = MbapSplitter::Status;

ByteVec adu(std::uint16_t tid, std::uint16_t pid, std::uint8_t unit, const ByteVec& pdu) {
    ByteVec out = {static_cast<std::uint8_t>(tid >> 8),
                   static_cast<std::uint8_t>(tid),
                   static_cast<std::uint8_t>(pid >> 8),
                   static_cast<std::uint8_t>(pid),
                   static_cast<std::uint8_t>((pdu.size() + 1) >> 8),
                   static_cast<std::uint8_t>(pdu.size() + 1),
                   unit};
    out.insert(out.end(), pdu.begin(), pdu.end());
    return out;
}

ByteVec raw_header(std::uint16_t tid, std::uint16_t pid, std::uint16_t length, std::uint8_t unit) {
    return {static_cast<std::uint8_t>(tid >> 8),
            static_cast<std::uint8_t>(tid),
            static_cast<std::uint8_t>(pid >> 8),
            static_cast<std::uint8_t>(pid),
            static_cast<std::uint8_t>(length >> 8),
            static_cast<std::uint8_t>(length),
            unit};
}

ByteVec max_pdu() {
    ByteVec pdu(limits::kMaxPdu);
    pdu[0] = 0x17;
    for (std::size_t i = 1; i < pdu.size(); ++i) pdu[i] = static_cast<std::uint8_t>(i * 7);
    return pdu;
}

struct Expected {
    Status status;
    ByteVec adu;
};

// A pipelined stream of mixed frames: minimum size (length 2), FC03 requests, a write,
// a maximum-size frame and a frame with protocol id != 0 in the middle.
std::vector<Expected> mixed_frames() {
    std::vector<Expected> f;
    f.push_back({Status::Frame, adu(1, 0, 0x11, {0x03, 0x00, 0x6B, 0x00, 0x03})});
    f.push_back({Status::Frame, adu(2, 0, 0xFF, {0x07})});
    f.push_back({Status::Frame,
                 adu(3, 0, 0x01, {0x10, 0x00, 0x01, 0x00, 0x02, 0x04, 0x00, 0x0A, 0x01, 0x02})});
    f.push_back({Status::BadProtocolId, adu(4, 0x0001, 0x01, {0x03, 0x00, 0x00, 0x00, 0x01})});
    f.push_back({Status::Frame, adu(5, 0, 0x02, max_pdu())});
    f.push_back({Status::Frame, adu(0xFFFF, 0, 0x00, {0x03, 0x00, 0x00, 0x00, 0x7D})});
    f.push_back({Status::BadProtocolId, adu(7, 0xFFFF, 0x09, {0x2B, 0x0E, 0x01, 0x00})});
    f.push_back({Status::Frame, adu(8, 0, 0x01, {0x01, 0x00, 0x13, 0x00, 0x25})});
    return f;
}

ByteVec concat(const std::vector<Expected>& frames) {
    ByteVec s;
    for (const auto& f : frames) s.insert(s.end(), f.adu.begin(), f.adu.end());
    return s;
}

struct Outcome {
    std::vector<Expected> frames;  // copies, since views die at the next call
    bool fatal = false;
    CodecError error = CodecError::Ok;
    std::size_t fatal_after_bytes = 0;  // stream bytes fed when Fatal first appeared
};

// Checks the invariants every returned frame must satisfy.
void check_frame_invariants(const TcpFrame& f) {
    ASSERT_EQ(f.adu.size(), f.header.length + 6u);
    ASSERT_EQ(f.pdu.size(), f.header.length - 1u);
    ASSERT_EQ(f.pdu.data(), f.adu.data() + 7);
    const MbapHeader h = read_mbap_header(f.adu.data());
    EXPECT_EQ(h.transaction_id, f.header.transaction_id);
    EXPECT_EQ(h.protocol_id, f.header.protocol_id);
    EXPECT_EQ(h.length, f.header.length);
    EXPECT_EQ(h.unit_id, f.header.unit_id);
}

// Feeds `stream` cut at the given (sorted) offsets and drains the splitter after each chunk.
Outcome run(const ByteVec& stream, const std::vector<std::size_t>& cuts) {
    MbapSplitter sp;
    Outcome o;
    std::size_t start = 0;
    std::vector<std::size_t> ends = cuts;
    ends.push_back(stream.size());
    for (std::size_t end : ends) {
        sp.feed(Bytes(stream.data() + start, end - start));
        while (true) {
            TcpFrame f;
            const Status st = sp.next(f);
            if (st == Status::NeedMore) {
                EXPECT_EQ(sp.pending(), 0u);
                break;
            }
            if (st == Status::Fatal) {
                o.fatal = true;
                o.error = sp.error();
                o.fatal_after_bytes = end;
                return o;
            }
            check_frame_invariants(f);
            o.frames.push_back({st, ByteVec(f.adu.begin(), f.adu.end())});
        }
        start = end;
    }
    EXPECT_EQ(sp.buffered(), 0u);
    return o;
}

void expect_frames(const Outcome& o, const std::vector<Expected>& want, const char* what) {
    ASSERT_EQ(o.frames.size(), want.size()) << what;
    for (std::size_t i = 0; i < want.size(); ++i) {
        EXPECT_EQ(o.frames[i].status, want[i].status) << what << " frame " << i;
        EXPECT_EQ(o.frames[i].adu, want[i].adu) << what << " frame " << i;
    }
}

TEST(MbapSplitter, WholeStreamInOneChunkYieldsViewsIntoTheChunk) {
    const auto want = mixed_frames();
    const ByteVec stream = concat(want);
    MbapSplitter sp;
    sp.feed(stream);
    std::size_t offset = 0;
    for (const auto& w : want) {
        TcpFrame f;
        ASSERT_EQ(sp.next(f), w.status);
        // Zero copy: the frame is a view at its position in the chunk.
        EXPECT_EQ(f.adu.data(), stream.data() + offset);
        EXPECT_EQ(ByteVec(f.adu.begin(), f.adu.end()), w.adu);
        offset += w.adu.size();
        EXPECT_EQ(sp.pending(), stream.size() - offset);
        EXPECT_EQ(sp.buffered(), 0u);
    }
    TcpFrame f;
    EXPECT_EQ(sp.next(f), Status::NeedMore);
    EXPECT_EQ(sp.next(f), Status::NeedMore);
}

TEST(MbapSplitter, EverySingleSplitPoint) {
    const auto want = mixed_frames();
    const ByteVec stream = concat(want);
    for (std::size_t cut = 0; cut <= stream.size(); ++cut) {
        const Outcome o = run(stream, {cut});
        ASSERT_FALSE(o.fatal) << "cut " << cut;
        expect_frames(o, want, "single cut");
    }
}

TEST(MbapSplitter, EveryPairOfSplitPoints) {
    const auto want = mixed_frames();
    const ByteVec stream = concat(want);
    for (std::size_t a = 0; a <= stream.size(); ++a) {
        for (std::size_t b = a; b <= stream.size(); ++b) {
            const Outcome o = run(stream, {a, b});
            ASSERT_FALSE(o.fatal) << a << "," << b;
            ASSERT_EQ(o.frames.size(), want.size()) << a << "," << b;
            for (std::size_t i = 0; i < want.size(); ++i) {
                ASSERT_EQ(o.frames[i].adu, want[i].adu) << a << "," << b << " frame " << i;
                ASSERT_EQ(o.frames[i].status, want[i].status);
            }
        }
    }
}

TEST(MbapSplitter, ByteByByte) {
    const auto want = mixed_frames();
    const ByteVec stream = concat(want);
    std::vector<std::size_t> cuts;
    for (std::size_t i = 1; i < stream.size(); ++i) cuts.push_back(i);
    const Outcome o = run(stream, cuts);
    ASSERT_FALSE(o.fatal);
    expect_frames(o, want, "byte by byte");
}

TEST(MbapSplitter, FrameSplitAcrossChunksIsAssembledInternally) {
    const ByteVec a = adu(9, 0, 1, {0x03, 0x00, 0x00, 0x00, 0x0A});
    MbapSplitter sp;
    TcpFrame f;
    sp.feed(Bytes(a.data(), 5));
    EXPECT_EQ(sp.next(f), Status::NeedMore);
    EXPECT_EQ(sp.buffered(), 5u);
    sp.feed(Bytes(a.data() + 5, 4));
    EXPECT_EQ(sp.next(f), Status::NeedMore);
    EXPECT_EQ(sp.buffered(), 9u);
    sp.feed(Bytes(a.data() + 9, a.size() - 9));
    ASSERT_EQ(sp.next(f), Status::Frame);
    EXPECT_EQ(sp.buffered(), 0u);
    EXPECT_EQ(f.header.transaction_id, 9);
    EXPECT_EQ(f.header.unit_id, 1);
    EXPECT_EQ(ByteVec(f.adu.begin(), f.adu.end()), a);
    // Assembled frames live in the splitter, not in the last chunk.
    EXPECT_FALSE(f.adu.data() >= a.data() && f.adu.data() < a.data() + a.size());
    EXPECT_EQ(sp.next(f), Status::NeedMore);
}

TEST(MbapSplitter, EmptyChunksAreHarmless) {
    const ByteVec a = adu(1, 0, 1, {0x03, 0x00, 0x00, 0x00, 0x01});
    MbapSplitter sp;
    TcpFrame f;
    sp.feed({});
    EXPECT_EQ(sp.next(f), Status::NeedMore);
    sp.feed(Bytes(a.data(), 3));
    EXPECT_EQ(sp.next(f), Status::NeedMore);
    sp.feed({});
    EXPECT_EQ(sp.next(f), Status::NeedMore);
    EXPECT_EQ(sp.buffered(), 3u);
    sp.feed(Bytes(a.data() + 3, a.size() - 3));
    EXPECT_EQ(sp.next(f), Status::Frame);
}

struct BadLength {
    std::uint16_t length;
    CodecError error;
};
constexpr BadLength kBadLengths[] = {
    {0, CodecError::LengthZero},         {1, CodecError::LengthOne},
    {255, CodecError::LengthTooLong},    {256, CodecError::LengthTooLong},
    {0xFFFF, CodecError::LengthTooLong},
};

TEST(MbapSplitter, BadLengthAtEveryFrameBoundaryAndEverySplitIsFatalAfterSevenBytes) {
    const auto good = mixed_frames();
    for (const auto& bad : kBadLengths) {
        for (std::uint16_t pid : {std::uint16_t{0}, std::uint16_t{5}}) {
            for (std::size_t pos = 0; pos <= good.size(); ++pos) {
                std::vector<Expected> before(good.begin(), good.begin() + pos);
                ByteVec stream = concat(before);
                const std::size_t bad_at = stream.size();
                const ByteVec h = raw_header(0x4242, pid, bad.length, 1);
                stream.insert(stream.end(), h.begin(), h.end());
                // Trailing garbage that must never be read as a frame.
                for (int i = 0; i < 20; ++i) stream.push_back(0x03);
                for (std::size_t cut = 0; cut <= stream.size(); ++cut) {
                    const Outcome o = run(stream, {cut});
                    ASSERT_TRUE(o.fatal)
                        << "len " << bad.length << " pos " << pos << " cut " << cut;
                    EXPECT_EQ(o.error, bad.error);
                    expect_frames(o, before, "frames before a bad header");
                    // Reported in the call that made the 7th header byte available.
                    const std::size_t header_done = bad_at + 7;
                    EXPECT_EQ(o.fatal_after_bytes, cut >= header_done ? cut : stream.size())
                        << "len " << bad.length << " pos " << pos << " cut " << cut;
                }
            }
        }
    }
}

TEST(MbapSplitter, BadLengthByteByByteIsReportedOnTheSeventhByte) {
    for (const auto& bad : kBadLengths) {
        const ByteVec good = adu(1, 0, 1, {0x03, 0x00, 0x00, 0x00, 0x01});
        ByteVec stream = good;
        const ByteVec h = raw_header(2, 0, bad.length, 1);
        stream.insert(stream.end(), h.begin(), h.end());
        std::vector<std::size_t> cuts;
        for (std::size_t i = 1; i < stream.size(); ++i) cuts.push_back(i);
        stream.push_back(0x00);  // one byte past the header: must not be needed
        cuts.push_back(stream.size() - 1);
        const Outcome o = run(stream, cuts);
        ASSERT_TRUE(o.fatal);
        EXPECT_EQ(o.error, bad.error);
        EXPECT_EQ(o.fatal_after_bytes, good.size() + 7);
        ASSERT_EQ(o.frames.size(), 1u);
    }
}

TEST(MbapSplitter, StaysFailedUntilReset) {
    const ByteVec bad = raw_header(1, 0, 0, 1);
    const ByteVec good = adu(1, 0, 1, {0x03, 0x00, 0x00, 0x00, 0x01});
    MbapSplitter sp;
    TcpFrame f;
    sp.feed(bad);
    EXPECT_EQ(sp.next(f), Status::Fatal);
    EXPECT_EQ(sp.error(), CodecError::LengthZero);
    sp.feed(good);
    EXPECT_EQ(sp.next(f), Status::Fatal);
    EXPECT_EQ(sp.error(), CodecError::LengthZero);
    sp.reset();
    EXPECT_EQ(sp.error(), CodecError::Ok);
    EXPECT_EQ(sp.pending(), 0u);
    EXPECT_EQ(sp.buffered(), 0u);
    sp.feed(good);
    EXPECT_EQ(sp.next(f), Status::Frame);
}

TEST(MbapSplitter, ResetDropsAPartialFrame) {
    const ByteVec good = adu(1, 0, 1, {0x03, 0x00, 0x00, 0x00, 0x01});
    MbapSplitter sp;
    TcpFrame f;
    sp.feed(Bytes(good.data(), 9));
    EXPECT_EQ(sp.next(f), Status::NeedMore);
    sp.reset();
    sp.feed(good);
    ASSERT_EQ(sp.next(f), Status::Frame);
    EXPECT_EQ(ByteVec(f.adu.begin(), f.adu.end()), good);
}

TEST(MbapSplitter, BadProtocolIdFrameIsSkippedAndTheStreamContinues) {
    const ByteVec a = adu(1, 0x1234, 1, {0x03, 0x00, 0x00, 0x00, 0x01});
    const ByteVec b = adu(2, 0, 1, {0x04, 0x00, 0x00, 0x00, 0x01});
    ByteVec s = a;
    s.insert(s.end(), b.begin(), b.end());
    MbapSplitter sp;
    sp.feed(s);
    TcpFrame f;
    ASSERT_EQ(sp.next(f), Status::BadProtocolId);
    EXPECT_EQ(f.header.protocol_id, 0x1234);
    EXPECT_EQ(f.pdu.size(), 5u);
    EXPECT_EQ(sp.error(), CodecError::Ok);
    ASSERT_EQ(sp.next(f), Status::Frame);
    EXPECT_EQ(f.header.transaction_id, 2);
}

TEST(MbapSplitter, ManySmallFramesInOneChunk) {
    ByteVec s;
    const int n = 1000;
    for (int i = 0; i < n; ++i) {
        const ByteVec a = adu(static_cast<std::uint16_t>(i), 0, 1,
                              {0x03, 0x00, static_cast<std::uint8_t>(i), 0x00, 0x0A});
        s.insert(s.end(), a.begin(), a.end());
    }
    MbapSplitter sp;
    sp.feed(s);
    TcpFrame f;
    int count = 0;
    while (sp.next(f) == Status::Frame) {
        EXPECT_EQ(f.header.transaction_id, count);
        EXPECT_EQ(f.pdu[2], static_cast<std::uint8_t>(count));
        ++count;
    }
    EXPECT_EQ(count, n);
}

TEST(MbapSplitter, MaximumFrameArrivingInTwoChunks) {
    const ByteVec a = adu(1, 0, 1, max_pdu());
    ASSERT_EQ(a.size(), limits::kMaxTcpAdu);
    for (std::size_t cut = 1; cut < a.size(); ++cut) {
        const Outcome o = run(a, {cut});
        ASSERT_FALSE(o.fatal);
        ASSERT_EQ(o.frames.size(), 1u);
        EXPECT_EQ(o.frames[0].adu, a);
    }
}

TEST(MbapSplitterNextModbus, PassesFramesOfAnotherProtocolByCountingThem) {
    ByteVec stream = adu(1, 0, 0x01, {0x03, 0x00, 0x00, 0x00, 0x01});
    const ByteVec other = adu(2, 0x0001, 0x01, {0x03, 0x00, 0x00, 0x00, 0x01});
    const ByteVec last = adu(3, 0, 0x01, {0x07});
    stream.insert(stream.end(), other.begin(), other.end());
    stream.insert(stream.end(), other.begin(), other.end());
    stream.insert(stream.end(), last.begin(), last.end());
    MbapSplitter splitter;
    splitter.feed(Bytes(stream.data(), stream.size()));
    TcpFrame frame;
    std::uint64_t skipped = 0;
    ASSERT_TRUE(splitter.next_modbus(frame, skipped));
    EXPECT_EQ(frame.header.transaction_id, 1);
    ASSERT_TRUE(splitter.next_modbus(frame, skipped));
    EXPECT_EQ(frame.header.transaction_id, 3);
    EXPECT_EQ(skipped, 2u);
    EXPECT_FALSE(splitter.next_modbus(frame, skipped));
    EXPECT_FALSE(splitter.failed());  // used up, not lost
}

TEST(MbapSplitterNextModbus, StopsAndSaysSoWhenTheFramingIsLost) {
    const ByteVec bad = raw_header(1, 0, 0, 0x01);  // length 0 cannot be resynchronised
    MbapSplitter splitter;
    splitter.feed(Bytes(bad.data(), bad.size()));
    TcpFrame frame;
    std::uint64_t skipped = 0;
    EXPECT_FALSE(splitter.next_modbus(frame, skipped));
    EXPECT_TRUE(splitter.failed());
    EXPECT_EQ(skipped, 0u);
}

}  // namespace
}  // namespace mbstorm::codec
