// The fuzzer in RTU and ASCII framing: frames cut from what was sent and received (with their
// MBAP views for the oracle), the generator's reframed cases and transport mutations, and the
// executor's verdicts over RTU over TCP against a slave in this test that either discards a
// frame with a bad CRC (conforming) or answers it.
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <pty.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <functional>
#include <memory>
#include <set>
#include <thread>
#include <vector>

#include "codec/mbap.hpp"
#include "codec/rtu.hpp"
#include "net/socket.hpp"
#include "netfuzz/case.hpp"
#include "netfuzz/executor.hpp"
#include "netfuzz/finding.hpp"
#include "netfuzz/generator.hpp"
#include "netfuzz/link.hpp"
#include "netfuzz/rules.hpp"
#include "netfuzz/serial_link.hpp"
#include "netfuzz/wire.hpp"
#include "thread_slave.hpp"

namespace mbstorm::netfuzz {
namespace {

using mbstorm::test::send_bytes;
using mbstorm::test::ThreadSlave;
using Bytes = std::vector<std::uint8_t>;
const Bytes kRead = {0x03, 0x00, 0x10, 0x00, 0x02};

TEST(WireCut, RtuRequestByFunctionCodeWithItsView) {
    Bytes f = frame_pdu(kRead, 0, 7, codec::Framing::Rtu);
    const Bytes next = frame_pdu({0x06, 0, 1, 0, 2}, 0, 7, codec::Framing::Rtu);
    Bytes stream = f;
    stream.insert(stream.end(), next.begin(), next.end());
    WireFrame w;
    ASSERT_EQ(cut_frame(stream, codec::Framing::Rtu, true, 0x42, w), WireCut::Frame);
    EXPECT_EQ(w.size, f.size());
    EXPECT_TRUE(w.discard.empty());
    EXPECT_EQ(w.mbap, frame_pdu(kRead, 0x42, 7));
    // Cut short: more is needed.
    EXPECT_EQ(cut_frame(codec::Bytes(f.data(), 5), codec::Framing::Rtu, true, 0, w),
              WireCut::NeedMore);
}

TEST(WireCut, RtuBadCrcIsToBeDiscarded) {
    Bytes f = frame_pdu(kRead, 0, 1, codec::Framing::Rtu);
    f.back() ^= 0x01;
    WireFrame w;
    ASSERT_EQ(cut_frame(f, codec::Framing::Rtu, true, 0, w), WireCut::Frame);
    EXPECT_EQ(w.discard, "bad-crc");
    EXPECT_EQ(w.size, f.size());
}

TEST(WireCut, RtuUnknownFunctionEndsAtItsCrc) {
    const Bytes f = frame_pdu({0x41, 0xAA, 0xBB}, 0, 1, codec::Framing::Rtu);
    WireFrame w;
    ASSERT_EQ(cut_frame(f, codec::Framing::Rtu, true, 0, w), WireCut::Frame);
    EXPECT_EQ(w.size, f.size());
    EXPECT_TRUE(w.discard.empty());
}

TEST(WireCut, RtuResponseLengths) {
    const Bytes rsp = frame_pdu({0x03, 0x04, 0, 1, 0, 2}, 0, 1, codec::Framing::Rtu);
    const Bytes exc = frame_pdu({0x83, 0x02}, 0, 1, codec::Framing::Rtu);
    WireFrame w;
    ASSERT_EQ(cut_frame(rsp, codec::Framing::Rtu, false, 9, w), WireCut::Frame);
    EXPECT_EQ(w.size, rsp.size());
    EXPECT_EQ(w.mbap, frame_pdu({0x03, 0x04, 0, 1, 0, 2}, 9, 1));
    ASSERT_EQ(cut_frame(exc, codec::Framing::Rtu, false, 0, w), WireCut::Frame);
    EXPECT_EQ(w.size, 5u);
}

TEST(WireCut, AsciiFramesNoiseAndBadLrc) {
    const Bytes f = frame_pdu(kRead, 0, 0x11, codec::Framing::Ascii);
    WireFrame w;
    ASSERT_EQ(cut_frame(f, codec::Framing::Ascii, true, 3, w), WireCut::Frame);
    EXPECT_EQ(w.size, f.size());
    EXPECT_TRUE(w.discard.empty());
    EXPECT_EQ(w.mbap, frame_pdu(kRead, 3, 0x11));
    Bytes noisy = {'x', 'y'};
    noisy.insert(noisy.end(), f.begin(), f.end());
    ASSERT_EQ(cut_frame(noisy, codec::Framing::Ascii, true, 0, w), WireCut::Frame);
    EXPECT_EQ(w.discard, "noise");
    EXPECT_EQ(w.size, 2u);
    std::size_t consumed = 0;
    EXPECT_EQ(request_views(noisy, codec::Framing::Ascii, consumed).size(), 1u);
    EXPECT_EQ(consumed, noisy.size());
    Bytes bad = f;
    bad[bad.size() - 3] = bad[bad.size() - 3] == '0' ? '1' : '0';
    ASSERT_EQ(cut_frame(bad, codec::Framing::Ascii, true, 0, w), WireCut::Frame);
    EXPECT_EQ(w.discard, "bad-lrc");
    EXPECT_EQ(cut_frame(codec::Bytes(f.data(), 6), codec::Framing::Ascii, true, 0, w),
              WireCut::NeedMore);
}

TEST(WireReframe, MbapFrameAsRtuAndAscii) {
    const Bytes m = frame_pdu(kRead, 0x1234, 5);
    EXPECT_EQ(reframe(m, codec::Framing::Rtu), frame_pdu(kRead, 0, 5, codec::Framing::Rtu));
    EXPECT_EQ(reframe(m, codec::Framing::Ascii), frame_pdu(kRead, 0, 5, codec::Framing::Ascii));
    EXPECT_EQ(reframe(m, codec::Framing::Mbap), m);
}

// Every case the generator makes in `framing` runs alone and holds no MBAP: what it sends cuts
// into frames of that framing (or is one frame in pieces).
std::set<MutationClass> generate(codec::Framing framing, bool serial, std::vector<Case>& out) {
    GeneratorOptions o;
    o.seed = 7;
    o.framing = framing;
    o.serial_line = serial;
    o.intercharacter_us = serial ? 860 : 0;
    o.isolated_per_mille = 300;
    Generator g(o);
    std::set<MutationClass> classes;
    for (int i = 0; i < 3000; ++i) {
        Case c;
        g.next(c);
        classes.insert(c.cls);
        out.push_back(std::move(c));
    }
    return classes;
}

TEST(GeneratorFraming, RtuOverTcpCasesAreRtuAndRunAlone) {
    std::vector<Case> cases;
    const auto classes = generate(codec::Framing::Rtu, false, cases);
    for (MutationClass mbap_only :
         {MutationClass::TransactionId, MutationClass::ProtocolId, MutationClass::MbapLength,
          MutationClass::TrailingBytes, MutationClass::Coalesced, MutationClass::BurstSplit})
        EXPECT_EQ(classes.count(mbap_only), 0u) << class_name(mbap_only);
    EXPECT_EQ(classes.count(MutationClass::BadChecksum), 1u);
    EXPECT_EQ(classes.count(MutationClass::Split), 1u);
    EXPECT_EQ(classes.count(MutationClass::BrokenSilence), 0u);  // a stream has no silences
    for (const Case& c : cases) {
        EXPECT_FALSE(c.pipelinable);
        // Whole frames, each with its CRC (a wrong one for bad-checksum), one per send; the
        // pieces of a split frame put back together are one frame.
        const bool pieces = c.cls == MutationClass::Split || c.cls == MutationClass::Drip ||
                            c.cls == MutationClass::PartialHold;
        if (c.cls == MutationClass::HalfClose || c.cls == MutationClass::Truncated) continue;
        Bytes all;
        for (const Step& s : c.steps) {
            if (s.op != Op::Send) continue;
            all.insert(all.end(), s.bytes.begin(), s.bytes.end());
            if (pieces) continue;
            EXPECT_EQ(rtu_crc_ok(s.bytes), c.cls != MutationClass::BadChecksum)
                << class_name(c.cls);
        }
        if (pieces) {
            EXPECT_TRUE(rtu_crc_ok(all)) << class_name(c.cls);
        }
    }
}

TEST(GeneratorFraming, SerialLinesGetSilenceAndNoiseMutationsOnOneLink) {
    for (codec::Framing framing : {codec::Framing::Rtu, codec::Framing::Ascii}) {
        std::vector<Case> cases;
        const auto classes = generate(framing, true, cases);
        EXPECT_EQ(classes.count(MutationClass::BadChecksum), 1u);
        EXPECT_EQ(classes.count(MutationClass::NoSilence), 1u);
        EXPECT_EQ(classes.count(MutationClass::Noise), 1u);
        EXPECT_EQ(classes.count(MutationClass::BrokenSilence),
                  framing == codec::Framing::Rtu ? 1u : 0u);
        for (const Case& c : cases) {
            for (const Step& s : c.steps) {
                EXPECT_EQ(s.conn, 0) << class_name(c.cls);
                EXPECT_NE(s.op, Op::Flood);
                EXPECT_NE(s.op, Op::SideProbe);
            }
            if (c.cls == MutationClass::BrokenSilence) {
                ASSERT_EQ(c.steps.size(), 2u);
                EXPECT_GT(c.steps[1].delay_us, 860u);  // longer than t1.5
            }
        }
    }
}

// A slave for RTU over TCP: answers every frame with exception 01 (illegal function), and a
// frame with a bad CRC too unless it `discards` those as it should.
class RtuSlave : public ThreadSlave {
  public:
    explicit RtuSlave(bool discards_bad_crc)
        : ThreadSlave([discards_bad_crc](int fd, Bytes& buf) {
              WireFrame w;
              while (cut_frame(buf, codec::Framing::Rtu, true, 0, w) == WireCut::Frame) {
                  const Bytes frame(buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(w.size));
                  buf.erase(buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(w.size));
                  if (!w.discard.empty() && discards_bad_crc) continue;
                  send_bytes(fd, frame_pdu({static_cast<std::uint8_t>(frame[1] | 0x80), 0x01}, 0,
                                           frame[0], codec::Framing::Rtu));
              }
          }) {}
};

Execution run_bad_crc_case(RtuSlave& slave) {
    net::Endpoint e = *net::parse_endpoint(slave.endpoint(), 502);
    TcpConnector connector(e, codec::Framing::Rtu);
    TargetProfile profile;
    profile.framing = codec::Framing::Rtu;
    profile.probe_pdu = kRead;
    Case c;
    c.cls = MutationClass::BadChecksum;
    Bytes f = frame_pdu(kRead, 0, 1, codec::Framing::Rtu);
    f.back() ^= 0x10;
    c.steps.push_back(Step{Op::Send, 0, 0, 0, f});
    ExecOptions o;
    o.timeout_ms = 400;
    return execute_case(c, connector, profile, o);
}

// A target that frames FC 08 by its function code and answers it (exception 01) as soon as
// it has read the header and the function code, before the rest of the frame came (libmodbus
// 3.1.6 answers a dripped FC 08 so): the answer carries the request's own transaction id, and
// its request is whole only after it. That is the stream-lost root cause, not an answer with a
// transaction id nobody sent.
TEST(ExecutorFraming, AnAnswerBeforeItsDrippedRequestWasWholeIsTheStreamLost) {
    auto early = std::make_shared<std::set<int>>();
    ThreadSlave slave([early](int fd, Bytes& buf) {
        while (buf.size() >= codec::limits::kMbapHeader + 1) {
            if (buf[7] == 0x08 && early->insert(fd).second)
                send_bytes(fd, {buf[0], buf[1], 0, 0, 0, 3, buf[6], 0x88, 0x01});
            const std::size_t whole = codec::announced_adu_size(buf.data());
            if (buf.size() < whole) return;
            if (buf[7] == 0x03)
                send_bytes(fd, {buf[0], buf[1], 0, 0, 0, 7, buf[6], 0x03, 4, 0, 0, 0, 0});
            early->erase(fd);
            buf.erase(buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(whole));
        }
    });
    net::Endpoint e = *net::parse_endpoint(slave.endpoint(), 502);
    TcpConnector connector(e);
    TargetProfile profile;
    profile.probe_pdu = kRead;
    Case c;
    c.cls = MutationClass::Drip;
    c.function = 0x08;
    const Bytes f = frame_pdu({0x08, 0x00, 0x11, 0x00, 0x00}, 0x816D, 1);
    c.steps.push_back(Step{Op::Send, 0, 0, 0, Bytes(f.begin(), f.begin() + 8)});
    c.steps.push_back(Step{Op::Send, 0, 50'000, 0, Bytes(f.begin() + 8, f.end())});
    ExecOptions o;
    o.timeout_ms = 300;
    const Execution ex = execute_case(c, connector, profile, o);
    EXPECT_EQ(root_cause_key(ex.verdict), std::string("stream:") + kStreamLostRule)
        << ex.verdict.summary;
}

// A server that answers frames whatever their protocol id and stops answering anyone for 2 s
// after an FC 14 (multi-fault bug 4): reached by a frame with protocol id 1, the whole-server
// hang is FC 14's handler's once the target is known to answer such frames (one defect, one
// finding: a coverage run had it twice, as .../fc14 and .../protocol-id), and the class's
// while it is not.
TEST(ExecutorFraming, AWholeServerHangThroughAnotherProtocolIdIsTheHandlersItReached) {
    auto blocked_until = std::make_shared<std::atomic<std::int64_t>>(0);
    ThreadSlave slave([blocked_until](int fd, Bytes& buf) {
        while (buf.size() >= codec::limits::kMbapHeader + 1) {
            const std::size_t whole = codec::announced_adu_size(buf.data());
            if (buf.size() < whole) return;
            const auto now = std::chrono::steady_clock::now().time_since_epoch().count();
            if (buf[7] == 0x14) blocked_until->store(now + 2'000'000'000);
            if (now >= blocked_until->load())
                send_bytes(fd, {buf[0], buf[1], buf[2], buf[3], 0, 7, buf[6], 0x03, 4, 0, 0, 0, 0});
            buf.erase(buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(whole));
        }
    });
    net::Endpoint e = *net::parse_endpoint(slave.endpoint(), 502);
    TcpConnector connector(e);
    Bytes f = frame_pdu({0x14, 0x07, 0x06, 0x00, 0x00, 0x00, 0x01, 0x00, 0x01}, 9, 1);
    f[3] = 0x01;  // protocol id 0001
    Case c;
    c.cls = MutationClass::ProtocolId;
    c.function = 0x14;
    c.steps.push_back(Step{Op::Send, 0, 0, 0, f});
    ExecOptions o;
    o.timeout_ms = 300;
    for (const bool answers : {false, true}) {
        TargetProfile profile;
        profile.probe_pdu = kRead;
        profile.answers_protocol_id = answers;
        blocked_until->store(0);
        const Execution ex = execute_case(c, connector, profile, o);
        EXPECT_EQ(root_cause_key(ex.verdict),
                  answers ? "hang:whole-server-hang/fc14" : "hang:whole-server-hang/protocol-id")
            << ex.verdict.summary;
    }
}

TEST(ExecutorFraming, SlaveThatDiscardsABadCrcAndAnswersTheNextFrameIsClean) {
    RtuSlave slave(true);
    const Execution e = run_bad_crc_case(slave);
    EXPECT_FALSE(e.verdict) << e.verdict.summary;
    // The in-stream probe after it was answered.
    bool answered = false;
    for (const TraceEvent& t : e.trace) answered = answered || t.kind == TraceKind::Recv;
    EXPECT_TRUE(answered);
}

TEST(ExecutorFraming, AnswerToABadCrcIsASpecDeviation) {
    RtuSlave slave(false);
    const Execution e = run_bad_crc_case(slave);
    EXPECT_EQ(e.verdict.oracle, Oracle::SpecDeviation);
    EXPECT_EQ(e.verdict.rule, "answers-bad-crc");
}

// A slave on a pseudo-terminal (the test holds the pty's master side) that cuts RTU frames by
// length alone, so it ignores silences: it answers every frame it cuts with exception 01, and
// a frame with a bad CRC too unless it `discards` those.
class PtySlave {
  public:
    explicit PtySlave(bool discards_bad_crc) : discards_(discards_bad_crc) {
        int slave = -1;
        char name[128] = {};
        if (::openpty(&pty_, &slave, name, nullptr, nullptr) != 0) return;
        ::close(slave);
        path_ = name;
        thread_ = std::thread([this] { serve(); });
    }
    ~PtySlave() {
        stop_ = true;
        if (thread_.joinable()) thread_.join();
        if (pty_ >= 0) ::close(pty_);
    }
    const std::string& path() const { return path_; }

  private:
    void serve() {
        Bytes buf;
        for (int rounds = 0; !stop_ && rounds < 20000; ++rounds) {
            pollfd p{pty_, POLLIN, 0};
            if (::poll(&p, 1, 10) <= 0) continue;
            std::uint8_t b[512];
            const ssize_t n = ::read(pty_, b, sizeof b);
            if (n <= 0) continue;
            buf.insert(buf.end(), b, b + n);
            WireFrame w;
            while (cut_frame(buf, codec::Framing::Rtu, true, 0, w) == WireCut::Frame) {
                const Bytes frame(buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(w.size));
                buf.erase(buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(w.size));
                if (!w.discard.empty() && discards_) continue;
                const Bytes answer = frame_pdu({static_cast<std::uint8_t>(frame[1] | 0x80), 0x01},
                                               0, frame[0], codec::Framing::Rtu);
                (void)!::write(pty_, answer.data(), answer.size());
            }
        }
    }
    bool discards_;
    int pty_ = -1;
    std::string path_;
    std::atomic<bool> stop_{false};
    std::thread thread_;
};

Execution run_on_line(PtySlave& slave, const Case& c) {
    net::SerialSettings line;
    line.parity = net::Parity::None;
    line.baud = 115200;
    SerialConnector connector(slave.path(), line, codec::Framing::Rtu);
    EXPECT_EQ(connector.max_links(), 1u);
    TargetProfile profile;
    profile.framing = codec::Framing::Rtu;
    profile.serial_line = true;
    profile.probe_pdu = kRead;
    ExecOptions o;
    o.timeout_ms = 300;
    return execute_case(c, connector, profile, o);
}

TEST(SerialFraming, BadCrcOnALineIsDiscardedByAConformingSlave) {
    Case c;
    c.cls = MutationClass::BadChecksum;
    Bytes f = frame_pdu(kRead, 0, 1, codec::Framing::Rtu);
    f[f.size() - 2] ^= 0x04;
    c.steps.push_back(Step{Op::Send, 0, 0, 0, f});
    PtySlave good(true);
    ASSERT_FALSE(good.path().empty());
    const Execution clean = run_on_line(good, c);
    EXPECT_FALSE(clean.verdict) << clean.verdict.summary;
    PtySlave bad(false);
    const Execution e = run_on_line(bad, c);
    EXPECT_EQ(e.verdict.rule, "answers-bad-crc") << e.verdict.summary;
}

TEST(SerialFraming, SlaveThatIgnoresAGapInsideAFrameAnswersABrokenFrame) {
    Case c;
    c.cls = MutationClass::BrokenSilence;
    const Bytes f = frame_pdu(kRead, 0, 1, codec::Framing::Rtu);
    c.steps.push_back(Step{Op::Send, 0, 0, 0, {f.begin(), f.begin() + 3}});
    c.steps.push_back(Step{Op::Send, 0, 2000, 0, {f.begin() + 3, f.end()}});
    PtySlave slave(true);
    ASSERT_FALSE(slave.path().empty());
    const Execution e = run_on_line(slave, c);
    EXPECT_EQ(e.verdict.oracle, Oracle::SpecDeviation) << e.verdict.summary;
    EXPECT_EQ(e.verdict.rule, "answers-broken-frame");
}

// A finding keeps the framing and the line it was found over (replay refuses another), and
// one saved before framings existed loads as MBAP.
TEST(FindingFraming, FramingAndLineSurviveSaveAndLoad) {
    Finding f;
    f.verdict = Verdict{Oracle::SpecDeviation, "answers-bad-crc", 0x03, "s", "e", "x"};
    f.fuzz_case.cls = MutationClass::BadChecksum;
    f.fuzz_case.steps = {Step{Op::Send, 0, 0, 0, frame_pdu(kRead, 0, 1, codec::Framing::Ascii)}};
    f.profile.probe_pdu = kRead;
    f.profile.framing = codec::Framing::Ascii;
    f.profile.serial_line = true;
    const auto dir = (std::filesystem::temp_directory_path() / "mbstorm-finding-framing").string();
    ASSERT_TRUE(save_finding(f, dir).ok());
    Result<Finding> loaded = load_finding(dir);
    ASSERT_TRUE(loaded.ok()) << loaded.error().text();
    Finding g = *loaded;
    EXPECT_EQ(g.profile.framing, codec::Framing::Ascii);
    EXPECT_TRUE(g.profile.serial_line);
    EXPECT_EQ(g.fuzz_case.cls, MutationClass::BadChecksum);
    f.profile = TargetProfile{};
    f.profile.probe_pdu = kRead;
    ASSERT_TRUE(save_finding(f, dir).ok());
    loaded = load_finding(dir);
    ASSERT_TRUE(loaded.ok()) << loaded.error().text();
    g = *loaded;
    EXPECT_EQ(g.profile.framing, codec::Framing::Mbap);
    EXPECT_FALSE(g.profile.serial_line);
    std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace mbstorm::netfuzz
