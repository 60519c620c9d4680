#include "netfuzz/executor.hpp"

#include <fmt/format.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>

#include "codec/function_code.hpp"
#include "codec/limits.hpp"
#include "codec/mbap.hpp"
#include "net/clock.hpp"
#include "netfuzz/cross_transport.hpp"
#include "netfuzz/death_watch.hpp"
#include "netfuzz/rules.hpp"
#include "netfuzz/state_marker.hpp"
#include "netfuzz/wire.hpp"

namespace mbstorm::netfuzz {
namespace {

namespace lim = codec::limits;
// A concurrent connection answered later than this was stalled by the case (loopback answers
// take well under a millisecond; a loaded machine stays far below this).
constexpr std::int64_t kStallMs = 250;

constexpr std::array<std::string_view, 11> kTraceNames = {
    "connect", "connect-failed", "send",  "recv",        "shutdown-write", "peer-closed",
    "reset",   "timeout",        "flood", "fresh-probe", "left-unread"};
static_assert(kTraceNames.size() == static_cast<std::size_t>(TraceKind::LeftUnread) + 1);

struct Pending {
    std::size_t offset = 0, size = 0;  // in Conn::sent
    std::uint16_t tid = 0;
    Expect expect = Expect::Answer;
    bool probe = false;
    // An in-stream probe sent only once the case's answers were awaited (a target that drops
    // what follows an exception): its answer shows the stream alive, not that nothing sent
    // before it was dropped.
    bool awaited_probe = false;
    std::int64_t sent_ns = 0, answered_ns = 0;
    std::size_t rsp_offset = 0, rsp_size = 0;  // in Conn::received
    // RTU/ASCII: gave up waiting for its answer (a later frame may then be answered)
    bool expired = false;
    std::string_view discard;  // RTU/ASCII: why a conforming reader drops it
};

struct Conn {
    std::unique_ptr<Link> link;
    bool opened = false, closed = false, reset = false, shut = false, desync = false;
    bool shut_after_frames = false;  // half-closed with every frame sent complete
    bool framing_lost = false;
    // The target closed it as soon as it read a piece of a frame, before the rest was due:
    // the size of that piece (0: it did not).
    std::size_t closed_on_piece = 0;
    std::vector<std::uint8_t> sent, received;
    std::size_t parsed = 0, rparsed = 0;
    std::vector<Pending> pending;
    std::vector<std::pair<std::size_t, std::size_t>> unmatched;  // responses nobody asked for
    // RTU/ASCII: the MBAP views of the frames sent and received, which Pending's offsets
    // point into (for MBAP they point into `sent` and `received`)
    std::vector<std::uint8_t> sview, rview;
    bool bad_response_check = false;  // RTU/ASCII: an answer's CRC/LRC failed
};

// Whether a request sent after the k-th on its connection was answered.
bool answered_after(const std::vector<Pending>& pending, std::size_t k) {
    return std::any_of(pending.begin() + static_cast<std::ptrdiff_t>(k) + 1, pending.end(),
                       [](const Pending& p) { return p.answered_ns != 0 && !p.awaited_probe; });
}

// Runs one case alone on its own connections and judges it; `BatchRunner` (batch.cpp) runs many
// well-framed cases pipelined over lanes.
class CaseRunner {
  public:
    CaseRunner(Connector& target, const TargetProfile& profile, const ExecOptions& options)
        : target_(target), profile_(profile), options_(options), start_(net::now_ns()) {}

    Execution run(const Case& c);

  private:
    void event(std::uint8_t conn, TraceKind kind, std::vector<std::uint8_t> bytes = {},
               std::string note = {}) {
        out_.trace.push_back(TraceEvent{(net::now_ns() - start_) / 1000, conn, kind,
                                        std::move(bytes), std::move(note)});
    }
    bool ensure_open(std::uint8_t index);
    void send_bytes(std::uint8_t index, const std::vector<std::uint8_t>& bytes);
    void parse_sent(Conn& c);
    void read_conn(std::uint8_t index);
    void parse_received(Conn& c);
    // RTU and ASCII framing (no transaction ids: one request in flight per link).
    bool framed() const noexcept { return profile_.framing != codec::Framing::Mbap; }
    const std::vector<std::uint8_t>& sent_frames(const Conn& c) const noexcept {
        return framed() ? c.sview : c.sent;
    }
    const std::vector<std::uint8_t>& received_frames(const Conn& c) const noexcept {
        return framed() ? c.rview : c.received;
    }
    void parse_sent_framed(Conn& c);
    void parse_received_framed(Conn& c);
    void add_framed_request(Conn& c, std::size_t size, const std::vector<std::uint8_t>& view,
                            std::string_view discard);
    // A serial line's silence ends a started RTU frame: what was sent of it is a broken frame.
    void close_partial(Conn& c);
    // One request in flight per link: waits for the answer to the one before (or, for one
    // that must or may be silent, a short while), then gives up on it.
    void await_in_flight(std::uint8_t index);
    // Pumps input until `done()` or the deadline. Returns false on timeout.
    template <typename Done>
    bool pump(std::int64_t deadline, Done done);
    bool answered(const Conn& c) const;
    void await_answers_before_probes();
    void flood(std::uint16_t count);
    void side_probe();
    // Before a gap: waits (boundedly) until the target's program has read what was sent on
    // the connection, so that the bytes after the gap reach it as a read of their own.
    void await_read_by_target(std::uint8_t index);
    bool wait_for_target_read(std::uint8_t index);  // false: not read, or not knowable
    // One step of a case: its gap first, then its operation.
    void perform(const Step& s);
    void close_out();
    void send_closing_probe(std::uint8_t index);
    bool await_close_out();  // false: the timeout came first
    // What judge() gathers across the connections: the worst verdict so far, and whom a
    // whole-server fault is blamed on.
    struct Judgement {
        Verdict candidate;
        std::vector<std::vector<RequestInfo>> infos;  // per connection, per pending request
        std::vector<Shadow::Event> shadow;
        bool need_fresh_probe = false;
        const RequestInfo* first_unanswered = nullptr;
        const RequestInfo* last_sent = nullptr;
        int last_fc = -1;
        void consider(Verdict v) {
            if (v && (!candidate || v.oracle < candidate.oracle)) candidate = std::move(v);
        }
    };
    void judge(const Case& c);
    void judge_framing(std::size_t i, const Conn& cn, Judgement& j) const;
    void judge_unmatched(const Conn& cn, Judgement& j) const;
    void judge_closed_on_piece(const Case& c, std::size_t i, const Conn& cn, Judgement& j) const;
    void judge_requests(const Case& c, std::size_t i, const Conn& cn, Judgement& j) const;
    void judge_silence(const Case& c, std::size_t i, const Conn& cn, std::size_t k,
                       const RequestInfo& info, const RequestInfo* before, bool before_exception,
                       Judgement& j) const;
    std::pair<std::string, const RequestInfo*> silence_rule(const Case& c, const Conn& cn,
                                                            std::size_t k, const RequestInfo& info,
                                                            const RequestInfo* before,
                                                            bool before_exception) const;
    void judge_side_probes(Judgement& j) const;
    void judge_flood(Judgement& j) const;
    void judge_target(const Case& c, Judgement& j);
    MutationClass whole_fault_class(const Case& c) const;
    // The marker register back at its initial value: the process restarted.
    bool marker_reset(const Judgement& j, std::uint16_t& seen);
    std::int64_t stall_threshold_ms() const {
        return std::min<std::int64_t>(kStallMs, options_.timeout_ms);
    }

    struct SideProbe {
        ProbeResult result;
        std::int64_t ms;
        std::string during;  // kPartialFrameCulprit, kExceptionHeld or kRequestHeld
    };

    Connector& target_;
    const TargetProfile& profile_;
    ExecOptions options_;
    std::int64_t start_;
    std::vector<Conn> conns_;
    Execution out_;
    bool any_connect_ = false;
    bool flooded_ = false;
    // Of the flood's connections: how many were open at once, and how many of those neither
    // answered nor closed in time (accepted, then left unserved).
    std::size_t flood_opened_ = 0, flood_silent_ = 0;
    std::vector<SideProbe> side_probes_;
    std::uint16_t view_tid_ = 1;  // RTU/ASCII: transaction ids of the MBAP views
};

bool CaseRunner::ensure_open(std::uint8_t index) {
    Conn& c = conns_[index];
    if (c.opened) return c.link != nullptr;
    c.opened = true;
    int error = 0;
    c.link = target_.open(options_.timeout_ms, error);
    if (!c.link) {
        event(index, TraceKind::ConnectFailed, {}, std::strerror(error));
        if (!any_connect_) out_.down_before = true;
        c.closed = true;
        return false;
    }
    any_connect_ = true;
    event(index, TraceKind::Connect);
    return true;
}

void CaseRunner::send_bytes(std::uint8_t index, const std::vector<std::uint8_t>& bytes) {
    Conn& c = conns_[index];
    if (!ensure_open(index) || c.closed || c.shut) return;
    bool await = framed() && c.parsed == c.sent.size();
    if (profile_.serial_line && profile_.framing == codec::Framing::Rtu &&
        c.parsed < c.sent.size()) {
        // The line's silence before these bytes ended the frame they were to finish: a
        // broken frame. Its answer is waited for only if these bytes are a frame of their
        // own (noise, then a frame); the rest of a frame split by a gap goes out at once, so
        // the gap stays as the case made it.
        close_partial(c);
        WireFrame whole;
        await = cut_frame(bytes, profile_.framing, true, 0, whole) == WireCut::Frame &&
                whole.size == bytes.size() && whole.discard.empty();
    }
    if (await) await_in_flight(index);
    if (c.closed) return;
    std::size_t done = 0;
    const std::int64_t deadline = net::now_ns() + options_.timeout_ms * net::kNsPerMs;
    while (done < bytes.size()) {
        const ssize_t n = c.link->send(bytes.data() + done, bytes.size() - done);
        if (n > 0) {
            done += static_cast<std::size_t>(n);
            continue;
        }
        if (n == -EAGAIN || n == 0) {
            if (net::now_ns() > deadline) break;
            // Drain input so that a server blocked on its own output can progress.
            read_conn(index);
            pollfd p{c.link->poll_fd(), POLLOUT, 0};
            ::poll(&p, 1, 10);
            continue;
        }
        c.closed = true;
        c.reset = n == -ECONNRESET || n == -EPIPE;
        event(index, TraceKind::Reset, {}, std::strerror(static_cast<int>(-n)));
        break;
    }
    if (done == 0) return;
    const std::int64_t now = net::now_ns();
    event(index, TraceKind::Send,
          {bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(done)});
    c.sent.insert(c.sent.end(), bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(done));
    const std::size_t before = c.pending.size();
    parse_sent(c);
    for (std::size_t i = before; i < c.pending.size(); ++i) c.pending[i].sent_ns = now;
}

// Cuts what we sent into request frames; anything that cannot be framed desynchronises the
// stream (the server's view of frame boundaries is then unknown, so no probe follows).
void CaseRunner::parse_sent(Conn& c) {
    if (framed()) {
        parse_sent_framed(c);
        return;
    }
    while (!c.desync && c.sent.size() - c.parsed >= lim::kMbapHeader) {
        const std::uint8_t* p = c.sent.data() + c.parsed;
        const codec::MbapHeader h = codec::read_mbap_header(p);
        const auto err = codec::check_mbap_header(h);
        if (err != codec::CodecError::Ok && err != codec::CodecError::BadProtocolId) {
            c.desync = true;
            return;
        }
        const std::size_t size = codec::adu_size(h);
        if (c.sent.size() - c.parsed < size) return;
        Pending pd;
        pd.offset = c.parsed;
        pd.size = size;
        pd.tid = h.transaction_id;
        pd.expect = h.protocol_id != 0 ? Expect::MustBeSilent
                    : (h.unit_id != profile_.unit || size == lim::kMbapHeader) ? Expect::MayBeSilent
                                                                               : Expect::Answer;
        c.pending.push_back(pd);
        c.parsed += size;
    }
}

void CaseRunner::read_conn(std::uint8_t index) {
    Conn& c = conns_[index];
    if (!c.link || c.closed) return;
    std::uint8_t buf[4096];
    for (;;) {
        const ssize_t n = c.link->recv(buf, sizeof buf);
        if (n > 0) {
            event(index, TraceKind::Recv, {buf, buf + n});
            c.received.insert(c.received.end(), buf, buf + n);
            parse_received(c);
            continue;
        }
        if (n == 0) {
            c.closed = true;
            event(index, TraceKind::PeerClosed);
            return;
        }
        if (n != -EAGAIN) {
            c.closed = true;
            c.reset = true;
            event(index, TraceKind::Reset, {}, std::strerror(static_cast<int>(-n)));
        }
        return;
    }
}

void CaseRunner::parse_received(Conn& c) {
    if (framed()) {
        parse_received_framed(c);
        return;
    }
    const std::int64_t now = net::now_ns();
    while (!c.framing_lost && c.received.size() - c.rparsed >= lim::kMbapHeader) {
        const codec::MbapHeader h = codec::read_mbap_header(c.received.data() + c.rparsed);
        if (h.length < 2 || h.length > lim::kMaxMbapLength) {
            c.framing_lost = true;
            return;
        }
        const std::size_t size = codec::adu_size(h);
        if (c.received.size() - c.rparsed < size) return;
        bool matched = false;
        for (Pending& pd : c.pending) {
            if (pd.answered_ns == 0 && pd.tid == h.transaction_id) {
                pd.answered_ns = now;
                pd.rsp_offset = c.rparsed;
                pd.rsp_size = size;
                matched = true;
                break;
            }
        }
        if (!matched) c.unmatched.emplace_back(c.rparsed, size);
        c.rparsed += size;
    }
}

void CaseRunner::add_framed_request(Conn& c, std::size_t size,
                                    const std::vector<std::uint8_t>& view,
                                    std::string_view discard) {
    Pending pd;
    pd.offset = c.sview.size();
    pd.size = view.size();
    pd.tid = codec::load_be16(view.data());
    pd.discard = discard;
    const std::uint8_t unit = view[lim::kMbapHeader - 1];
    if (!discard.empty()) {
        pd.expect = Expect::MustBeSilent;
    } else if (unit == 0 && profile_.serial_line) {
        pd.expect = Expect::MustBeSilent;  // a broadcast: executed, never answered
        pd.discard = "broadcast";
    } else if (unit != profile_.unit || view.size() == lim::kMbapHeader) {
        pd.expect = Expect::MayBeSilent;
    }
    c.sview.insert(c.sview.end(), view.begin(), view.end());
    c.pending.push_back(pd);
    c.parsed += size;
}

void CaseRunner::parse_sent_framed(Conn& c) {
    while (!c.desync && c.parsed < c.sent.size()) {
        WireFrame f;
        const WireCut cut =
            cut_frame(codec::Bytes(c.sent).subspan(c.parsed), profile_.framing, true, view_tid_, f);
        const codec::Bytes rest = codec::Bytes(c.sent).subspan(c.parsed);
        if (profile_.framing == codec::Framing::Rtu &&
            (cut != WireCut::Frame || !f.discard.empty()) && rtu_crc_ok(rest)) {
            // A PDU longer or shorter than its function code says, sent as one frame with its
            // CRC: a reader that frames by length sees a bad CRC (or waits), one that frames by
            // silence an invalid request. Either may stay silent; the stream's boundaries are
            // lost for the first kind, so over TCP nothing after it is owed.
            add_framed_request(c, rest.size(),
                               mbap_view(rest[0], rest.subspan(1, rest.size() - 3), view_tid_++),
                               {});
            if (c.pending.back().expect == Expect::Answer)
                c.pending.back().expect = Expect::MayBeSilent;
            if (!profile_.serial_line) c.desync = true;
            return;
        }
        if (cut == WireCut::NeedMore) return;
        if (cut == WireCut::Lost) {
            if (!profile_.serial_line) {
                c.desync = true;  // nothing tells the server where a frame ends either
                return;
            }
            close_partial(c);  // on a line, the silence after it ends it
            return;
        }
        ++view_tid_;
        if (f.discard == "noise") {
            c.parsed += f.size;  // skipped by any reader looking for ':'; owed nothing
            continue;
        }
        add_framed_request(c, f.size, f.mbap, f.discard);
    }
}

void CaseRunner::close_partial(Conn& c) {
    if (c.desync || c.parsed >= c.sent.size()) return;
    const codec::Bytes rest = codec::Bytes(c.sent).subspan(c.parsed);
    add_framed_request(c, rest.size(), mbap_view(rest[0], rest.subspan(1), view_tid_++),
                       "broken-frame");
}

void CaseRunner::parse_received_framed(Conn& c) {
    const std::int64_t now = net::now_ns();
    while (!c.framing_lost && c.rparsed < c.received.size()) {
        // The answer belongs to the one request in flight.
        Pending* in_flight = nullptr;
        for (Pending& pd : c.pending) {
            if (pd.answered_ns == 0 && !pd.expired) {
                in_flight = &pd;
                break;
            }
        }
        WireFrame f;
        const WireCut cut = cut_frame(codec::Bytes(c.received).subspan(c.rparsed), profile_.framing,
                                      false, in_flight ? in_flight->tid : 0, f);
        if (cut == WireCut::NeedMore) return;
        if (cut == WireCut::Lost || !f.discard.empty()) {
            c.framing_lost = true;
            c.bad_response_check = cut == WireCut::Frame;
            return;
        }
        const std::size_t offset = c.rview.size();
        c.rview.insert(c.rview.end(), f.mbap.begin(), f.mbap.end());
        if (in_flight) {
            in_flight->answered_ns = now;
            in_flight->rsp_offset = offset;
            in_flight->rsp_size = f.mbap.size();
        } else if (!c.desync) {
            // (After a desync, frames sent but not cut may be answered: owed nothing, yet not
            // unasked either.)
            c.unmatched.emplace_back(offset, f.mbap.size());
        }
        c.rparsed += f.size;
    }
}

void CaseRunner::await_in_flight(std::uint8_t index) {
    Conn& c = conns_[index];
    for (std::size_t k = 0; k < c.pending.size(); ++k) {
        if (c.pending[k].answered_ns || c.pending[k].expired) continue;
        // A frame owed silence is watched for a late answer, which would otherwise be taken
        // for the next request's: as long as one owed an answer, or as the campaign says from
        // how slowly the target answers at worst.
        const int watch_ms = c.pending[k].expect != Expect::Answer && options_.silence_watch_ms
                                 ? std::min(options_.silence_watch_ms, options_.timeout_ms)
                                 : options_.timeout_ms;
        pump(net::now_ns() + std::int64_t{watch_ms} * net::kNsPerMs,
             [&] { return c.pending[k].answered_ns != 0 || c.closed; });
        if (!c.pending[k].answered_ns) c.pending[k].expired = true;
        if (c.closed) return;
    }
}

bool CaseRunner::answered(const Conn& c) const {
    if (c.closed || c.framing_lost || !c.unmatched.empty()) return true;
    for (const Pending& pd : c.pending)
        if (pd.expect == Expect::Answer && pd.answered_ns == 0 && !pd.expired) return false;
    return true;
}

// A target that drops what follows an exception (libmodbus's flush) would drop an in-stream
// probe sent right behind the case, and each such case would cost a timeout: the case's own
// answers are awaited first. Such a target flushes before it answers, so a probe sent once the
// exception has arrived is read.
void CaseRunner::await_answers_before_probes() {
    if (!profile_.drops_after_exception) return;
    pump(net::now_ns() + options_.timeout_ms * net::kNsPerMs, [&] {
        return std::all_of(conns_.begin(), conns_.end(), [&](const Conn& cn) {
            return !cn.opened || !cn.link || cn.shut || cn.desync || answered(cn);
        });
    });
}

template <typename Done>
bool CaseRunner::pump(std::int64_t deadline, Done done) {
    std::vector<pollfd> fds;
    for (;;) {
        if (done()) return true;
        const std::int64_t now = net::now_ns();
        if (now >= deadline) return false;
        fds.clear();
        bool buffered = false;
        for (const Conn& c : conns_)
            if (c.link && !c.closed) {
                fds.push_back(pollfd{c.link->poll_fd(), POLLIN, 0});
                buffered = buffered || c.link->has_buffered_input();
            }
        if (fds.empty()) return done();
        const int wait_ms =
            static_cast<int>(std::max<std::int64_t>(1, (deadline - now) / net::kNsPerMs));
        ::poll(fds.data(), fds.size(), buffered ? 0 : std::min(wait_ms, 50));
        for (std::size_t i = 0; i < conns_.size(); ++i)
            if (conns_[i].link && !conns_[i].closed) read_conn(static_cast<std::uint8_t>(i));
    }
}

void CaseRunner::flood(std::uint16_t count) {
    flooded_ = true;
    event(0, TraceKind::Flood, {}, fmt::format("{} connections", count));
    // Every link opened (within one timeout, and 2 ms more per connection, in all: a thousand
    // connects on a loaded host take a while) gets one probe; answers are not awaited.
    std::vector<std::unique_ptr<Link>> links;
    const std::int64_t deadline =
        net::now_ns() +
        (options_.timeout_ms + 2 * static_cast<std::int64_t>(count)) * net::kNsPerMs;
    const std::uint16_t n =
        static_cast<std::uint16_t>(std::min<unsigned>(count, target_.max_links()));
    for (std::uint16_t i = 0; i < n; ++i) {
        const std::int64_t left_ms = (deadline - net::now_ns()) / net::kNsPerMs;
        if (left_ms <= 0) break;
        int error = 0;
        auto link = target_.open(static_cast<int>(left_ms), error);
        if (!link) continue;
        const auto f = probe_frame(profile_, i);
        (void)link->send(f.data(), f.size());
        links.push_back(std::move(link));
    }
    // All of them held until each is answered or closed (or a timeout): a server that fails
    // at N connections must have N at once. As long as the capacity check waits (capacity.cpp):
    // slow is not unserved.
    std::vector<pollfd> waiting;
    for (const auto& link : links) waiting.push_back(pollfd{link->poll_fd(), POLLIN, 0});
    const std::int64_t until =
        net::now_ns() +
        (3 * options_.timeout_ms + 2 * static_cast<std::int64_t>(links.size())) * net::kNsPerMs;
    while (!waiting.empty() && net::now_ns() < until) {
        if (::poll(waiting.data(), waiting.size(), 20) <= 0) continue;
        std::erase_if(waiting, [](const pollfd& p) { return p.revents != 0; });
    }
    flood_opened_ = std::max(flood_opened_, links.size());
    flood_silent_ += waiting.size();
}

// Connections accepted and then left unserved: what the capacity check calls a hang, so that
// its finding replays as itself.
void CaseRunner::judge_flood(Judgement& j) const {
    if (flood_silent_ == 0) return;
    j.consider(Verdict{
        Oracle::Hang, kCapacityUnservedRule, -1,
        fmt::format("with {} connections opened at once, {} accepted connection(s) got no answer",
                    flood_opened_, flood_silent_),
        "every accepted connection is served (or refused, or closed, at a limit)",
        fmt::format("{} of {} silent", flood_silent_, flood_opened_)});
}

void CaseRunner::judge_framing(std::size_t i, const Conn& cn, Judgement& j) const {
    if (!cn.framing_lost) return;
    if (framed()) {
        j.consider(Verdict{
            Oracle::MalformedResponse,
            cn.bad_response_check ? kResponseCheckFailedRule : kResponseFramingRule, -1,
            fmt::format(
                "response framing lost on connection {}: {}", i,
                cn.bad_response_check
                    ? std::string(profile_.framing == codec::Framing::Rtu ? "bad CRC" : "bad LRC")
                    : std::string("no frame can start here")),
            "well-framed answers with a good CRC/LRC",
            hex(codec::Bytes(cn.received).subspan(cn.rparsed))});
        return;
    }
    j.consider(Verdict{Oracle::MalformedResponse, kResponseFramingRule, -1,
                       fmt::format("response framing lost on connection {}: MBAP length {}", i,
                                   codec::read_mbap_header(cn.received.data() + cn.rparsed).length),
                       "MBAP length 2..254", hex(codec::Bytes(cn.received).subspan(cn.rparsed))});
}

// TCP is a stream: a frame may reach a server in any number of reads. One that closes on the
// first piece, before the rest could come, breaks every client whose frame the network splits.
void CaseRunner::judge_closed_on_piece(const Case& c, std::size_t i, const Conn& cn,
                                       Judgement& j) const {
    if (!cn.closed_on_piece) return;
    j.consider(
        Verdict{Oracle::UnexpectedClose, kClosesOnPartialFrameRule, c.function,
                fmt::format("connection {} {} as soon as the target read {} ({} byte(s) "
                            "of a frame), before the rest was sent",
                            i, cn.reset ? "reset" : "closed",
                            hex(codec::Bytes(cn.sent).subspan(cn.parsed), 16), cn.closed_on_piece),
                "the rest awaited, the whole frame answered", cn.reset ? "reset" : "FIN"});
    j.need_fresh_probe = true;
}

void CaseRunner::judge_unmatched(const Conn& cn, Judgement& j) const {
    // An answer nobody asked for, on a connection that carried a request of the wrong
    // length, is the target framing that request by its function code.
    bool length_mismatch_sent = false, own_request = false;
    const std::vector<std::uint8_t>& sent_frames_of = sent_frames(cn);
    const std::vector<std::uint8_t>& received_frames_of = received_frames(cn);
    for (const Pending& pd : cn.pending) {
        own_request = own_request || !pd.probe;
        if (pd.probe || pd.size < lim::kMbapHeader) continue;
        RequestInfo sent;
        describe_request(codec::Bytes(sent_frames_of.data() + pd.offset, pd.size), profile_, sent);
        length_mismatch_sent = length_mismatch_sent || pdu_length_mismatch(sent);
    }
    // Nothing complete was sent on it: the target took a started frame for a whole one. An
    // answer carrying the started frame's own transaction id read its header and framed it by
    // the function code, not the MBAP length (libmodbus answers a half-closed FC 15 whose data
    // never came): the stream-lost root cause. Any other answer is its reassembly decoding
    // a partial buffer (pymodbus answers a bare header, or three bytes of one, with 0000).
    const std::size_t started = cn.sent.size() - cn.parsed;
    const bool partial_only = !own_request && started > 0;
    const int started_tid = partial_only && started >= lim::kMbapHeader
                                ? codec::load_be16(cn.sent.data() + cn.parsed)
                                : -1;
    for (const auto& [off, size] : cn.unmatched) {
        std::string tids;
        for (const Pending& pd : cn.pending)
            tids += fmt::format("{}{:04X}", tids.empty() ? "" : ",", pd.tid);
        // Whose answer it most likely is: an unanswered request of the same function.
        int fc = -1;
        if (size > lim::kMbapHeader) {
            const std::uint8_t rfc = received_frames_of[off + lim::kMbapHeader] & 0x7F;
            for (const Pending& pd : cn.pending)
                if (!pd.answered_ns && pd.size > lim::kMbapHeader &&
                    sent_frames_of[pd.offset + lim::kMbapHeader] == rfc)
                    fc = rfc;
        }
        const int tid = codec::load_be16(received_frames_of.data() + off);
        // The transaction id of a request still unanswered, sent whole only after this answer
        // came (a frame dripped a byte at a time): a started frame answered, the same guise.
        bool answered_before_whole = false;
        for (const Pending& pd : cn.pending)
            answered_before_whole =
                answered_before_whole || (!pd.probe && !pd.answered_ns && pd.tid == tid);
        j.consider(Verdict{Oracle::MalformedResponse,
                           length_mismatch_sent || tid == started_tid || answered_before_whole
                               ? kStreamLostRule
                           : partial_only ? kAnswersPartialFrameRule
                                          : kUnmatchedTransactionIdRule,
                           fc,
                           fmt::format("response with transaction id {:04X} matches no request",
                                       codec::load_be16(received_frames_of.data() + off)),
                           fmt::format("transaction ids {}", tids),
                           hex(codec::Bytes(received_frames_of.data() + off, size))});
    }
}

// The rule a silence (or close) on the request at `k` breaks, and the request it is blamed on.
std::pair<std::string, const RequestInfo*> CaseRunner::silence_rule(const Case& c, const Conn& cn,
                                                                    std::size_t k,
                                                                    const RequestInfo& info,
                                                                    const RequestInfo* before,
                                                                    bool before_exception) const {
    const Pending& pd = cn.pending[k];
    const bool closed = cn.closed;
    const RequestInfo* blamed = pd.probe ? before : &info;
    // A target known to drop what follows an exception, that answered the request
    // before with one, dropped the rest for that, however long the request was.
    // (After our half-close, the close that follows is owed.)
    // A stream that went on (a later request on it was answered) neither was lost nor
    // dropped what followed the request before: the silence is this request's own.
    if (answered_after(cn.pending, k)) before = nullptr;
    const bool exception_drop =
        before && before_exception && profile_.drops_after_exception && (!closed || cn.shut);
    if (exception_drop) return {kDropsRequestsAfterExceptionRule, before};
    // The same valid request, answered before: nothing in it is to blame.
    if (c.cls == MutationClass::Repeated)
        return {closed ? kRandomCloseRule : kRandomDropRule, nullptr};
    if (cn.shut) return {kDropsAnswersOnHalfCloseRule, blamed};
    if (before && pdu_length_mismatch(*before)) return {kStreamLostRule, before};
    if (!pd.probe && closed && pdu_length_mismatch(info)) return {kStreamLostRule, blamed};
    // Closing on a request it cannot use is one policy of the server's framing, whatever the
    // function code; and it is the likelier cause than the exception answered before it
    // (pymodbus closes on a short FC 10 however the requests before it were answered: two
    // findings for one defect, until this came first).
    if (closed && !pd.probe && request_kind(info) != "valid")
        return {kClosesOnInvalidRequestRule, blamed};
    if (before && before_exception) return {after_exception_rule(closed), before};
    if (!pd.probe || !before)
        return {unanswered_rule(closed, culprit_text(c.cls, pd.probe ? nullptr : &info)), blamed};
    return {after_request_rule(closed, culprit_text(c.cls, before)), blamed};
}

void CaseRunner::judge_silence(const Case& c, std::size_t i, const Conn& cn, std::size_t k,
                               const RequestInfo& info, const RequestInfo* before,
                               bool before_exception, Judgement& j) const {
    const Pending& pd = cn.pending[k];
    // RTU over TCP: after a frame it must discard (a bad CRC) a server may close the
    // stream, whose frame boundaries it can no longer trust; it must not answer it.
    if (cn.closed && framed() && !profile_.serial_line && before && !before->discard.empty())
        return;
    auto [rule, blamed] = silence_rule(c, cn, k, info, before, before_exception);
    const std::string what = pd.probe ? std::string("the in-stream liveness probe")
                                      : fmt::format("request {}", hex(info.pdu, 16));
    const int fc = blamed && !blamed->pdu.empty() ? blamed->pdu[0] : -1;
    // A drop behind an exception is the same fault whether or not our half-close then
    // (rightly) closed the connection.
    const bool exception_drop = rule == kDropsRequestsAfterExceptionRule && cn.shut;
    if (cn.closed && !exception_drop) {
        j.consider(Verdict{
            Oracle::UnexpectedClose, std::move(rule), fc,
            fmt::format("connection {} {} with {} unanswered{}", i, cn.reset ? "reset" : "closed",
                        what, cn.shut ? " after our half-close" : ""),
            "an answer, connection kept open", cn.reset ? "reset" : "FIN"});
    } else {
        j.consider(Verdict{Oracle::Hang, std::move(rule), fc,
                           fmt::format("no answer to {} within {} ms on open connection {}", what,
                                       options_.timeout_ms, i),
                           "an answer", "silence"});
    }
    j.need_fresh_probe = true;
}

void CaseRunner::judge_requests(const Case& c, std::size_t i, const Conn& cn, Judgement& j) const {
    const std::vector<std::uint8_t>& sent_frames_of = sent_frames(cn);
    const std::vector<std::uint8_t>& received_frames_of = received_frames(cn);
    j.infos[i].resize(cn.pending.size());
    // The case's own request before the current one on this connection, and whether it
    // drew an exception: silence after it is blamed on it.
    const RequestInfo* prev_own = nullptr;
    bool prev_exception = false;
    bool reported = false;  // only the first unanswered request per connection: the
                            // silence after it follows from it
    for (std::size_t k = 0; k < cn.pending.size(); ++k) {
        const Pending& pd = cn.pending[k];
        RequestInfo& info = j.infos[i][k];
        describe_request(codec::Bytes(sent_frames_of.data() + pd.offset, pd.size), profile_, info);
        if (framed()) {  // the frame's own expectation: a discarded or broadcast frame
            info.expect = pd.expect;
            info.discard = pd.discard;
        }
        bool exception = false;
        if (pd.answered_ns) {
            const codec::Bytes rsp(received_frames_of.data() + pd.rsp_offset, pd.rsp_size);
            j.consider(judge_response(info, rsp, profile_));
            j.shadow.push_back(Shadow::Event{&info, pd.sent_ns, pd.answered_ns,
                                             rsp.subspan(lim::kMbapHeader),
                                             static_cast<std::uint8_t>(i)});
            // Not a normal answer: an exception, or a function code that is not the
            // request's (libmodbus answers 0x39 for an unknown 0xB9), which a server may
            // follow with the same flush as an exception.
            exception = rsp.size() > lim::kMbapHeader && !info.pdu.empty() &&
                        ((rsp[lim::kMbapHeader] & codec::kExceptionBit) != 0 ||
                         rsp[lim::kMbapHeader] != info.pdu[0]);
        } else {
            j.shadow.push_back(Shadow::Event{&info, pd.sent_ns, 0, {}});
        }
        const RequestInfo* before = prev_own;
        const bool before_exception = prev_exception;
        if (!pd.probe) {
            prev_own = &info;
            prev_exception = exception;
            j.last_sent = &info;
            if (!info.pdu.empty()) j.last_fc = info.pdu[0];
        }
        if (pd.expect != Expect::Answer || pd.answered_ns || reported) continue;
        // A server may drop what it has not answered when a frame was left unfinished;
        // complete frames before a clean half-close are still owed their answers.
        if (cn.desync || (cn.shut && !cn.shut_after_frames)) continue;
        // Answers that matched nothing or lost framing: the missing answer is already
        // explained by the malformed response.
        if (!cn.unmatched.empty() || cn.framing_lost) continue;
        reported = true;
        if (!pd.probe && !j.first_unanswered) j.first_unanswered = &info;
        judge_silence(c, i, cn, k, info, before, before_exception, j);
    }
}

void CaseRunner::judge_side_probes(Judgement& j) const {
    for (const SideProbe& sp : side_probes_) {
        const bool stalled = sp.result != ProbeResult::Ok || sp.ms >= stall_threshold_ms();
        if (!stalled || sp.result == ProbeResult::ConnectFailed) continue;
        j.consider(Verdict{
            Oracle::Hang, stalls_other_connections_rule(sp.during), j.last_fc,
            fmt::format("a concurrent connection {} ({} ms) while another held {}",
                        sp.result == ProbeResult::Ok
                            ? std::string("was answered late")
                            : fmt::format("got {}", probe_result_name(sp.result)),
                        sp.ms,
                        sp.during == kPartialFrameCulprit ? "a started frame"
                        : sp.during == kExceptionHeld     ? "a request answered with an exception"
                                                          : "a request"),
            fmt::format("an answer within {} ms, whatever other connections do",
                        stall_threshold_ms()),
            fmt::format("{} after {} ms", probe_result_name(sp.result), sp.ms)});
    }
}

bool CaseRunner::marker_reset(const Judgement& j, std::uint16_t& seen) {
    StateMarker* m = options_.marker;
    if (options_.watch || !m || !m->armed()) return false;
    for (const auto& conn : j.infos)
        for (const RequestInfo& info : conn)
            if (may_write_register(info.pdu, m->address())) {
                m->rearm();  // this case may have written it: nothing to be told from it
                return false;
            }
    const StateMarker::Reading reading = m->read(seen);
    event(kFreshConn, TraceKind::FreshProbe, {},
          reading == StateMarker::Reading::Reset ? "marker register lost its value"
                                                 : "marker register kept");
    return reading == StateMarker::Reading::Reset;
}

// Whether the target is still there (the fresh probe, then the sentinels): a death or a
// whole-server hang outranks whatever the case's own connections showed.
// The class a whole-server fault's culprit is named by: a frame with a protocol id other than 0
// that the target answers reached its function's handler (TargetProfile::answers_protocol_id).
MutationClass CaseRunner::whole_fault_class(const Case& c) const {
    return c.cls == MutationClass::ProtocolId && profile_.answers_protocol_id
               ? MutationClass::ValidLimits
               : c.cls;
}

void CaseRunner::judge_target(const Case& c, Judgement& j) {
    // The fresh probe goes first: on a loaded machine the kernel may deliver the sentinels'
    // closes a little after the case's own; loopback packets are taken in order, so by the
    // time the probe is answered they have arrived.
    ProbeResult r = ProbeResult::Ok;
    if (j.need_fresh_probe) {
        // A target that serves one connection at a time gets to the probe only once the
        // case's own are gone.
        if (profile_.one_connection)
            for (Conn& cn : conns_) cn.link.reset();
        r = probe_target(target_, profile_, options_.timeout_ms);
        event(kFreshConn, TraceKind::FreshProbe, {}, std::string(probe_result_name(r)));
    }
    if (options_.watch && options_.watch->died(j.need_fresh_probe ? 200 : 20)) {
        // The process died, whatever brought it back: every connection it held is gone.
        event(kFreshConn, TraceKind::FreshProbe, {}, "every idle sentinel connection dropped");
        out_.target_down = true;
        j.candidate = fresh_probe_verdict(ProbeResult::Closed);
        j.candidate.summary =
            "the target's process died: every idle connection it held was closed at once";
    } else if (options_.process_exited && options_.process_exited()) {
        event(kFreshConn, TraceKind::FreshProbe, {}, "the target's process exited");
        out_.target_down = true;
        j.candidate = fresh_probe_verdict(ProbeResult::Closed);
        j.candidate.summary = "the target's process exited during the case";
    } else if (j.need_fresh_probe) {
        if (r == ProbeResult::Closed || r == ProbeResult::ConnectFailed) {
            // A process that is dying may still complete a connect from its backlog, and a
            // busy one may let a connect wait out a full backlog: look again a moment later
            // before calling it a crash.
            ::usleep(r == ProbeResult::Closed ? 50000 : 200000);
            r = probe_target(target_, profile_, options_.timeout_ms);
            event(kFreshConn, TraceKind::FreshProbe, {}, std::string(probe_result_name(r)));
        }
        // A case asking whether the target drops requests at random: its probe's silence
        // is one more such drop, not a whole-server hang.
        if (c.cls == MutationClass::Repeated && r == ProbeResult::NoAnswer) r = ProbeResult::Ok;
        // Likewise after a flood that left accepted connections unserved: the probe is one
        // more connection past the target's limit (it may not have seen the flood's close yet).
        if (flood_silent_ > 0 && r == ProbeResult::NoAnswer) r = ProbeResult::Ok;
        if (r != ProbeResult::Ok) {
            out_.target_down = r == ProbeResult::ConnectFailed || r == ProbeResult::Closed;
            j.candidate = fresh_probe_verdict(r);
        }
    }
    std::uint16_t seen = 0;
    if (j.need_fresh_probe && !out_.target_down && r == ProbeResult::Ok && marker_reset(j, seen)) {
        out_.target_down = true;
        j.candidate = fresh_probe_verdict(ProbeResult::Closed);
        j.candidate.summary = fmt::format(
            "the target's process restarted: holding register {} held {:04X}, not the {:04X} "
            "mbstorm had written there",
            options_.marker->address(), seen, options_.marker->value());
    }
    if (out_.target_down || (j.need_fresh_probe && r != ProbeResult::Ok)) {
        // The request a whole-server fault is blamed on: the first one owed an answer that
        // got none, else the last one sent.
        const RequestInfo* at = j.first_unanswered ? j.first_unanswered : j.last_sent;
        j.candidate.rule =
            rule_with_culprit(j.candidate.rule, culprit_text(whole_fault_class(c), at));
        j.candidate.culprit_fc = at && !at->pdu.empty() ? at->pdu[0] : -1;
    }
}

void CaseRunner::judge(const Case& c) {
    Judgement j;
    j.infos.resize(conns_.size());
    j.need_fresh_probe = flooded_;
    for (std::size_t i = 0; i < conns_.size(); ++i) {
        const Conn& cn = conns_[i];
        if (!cn.opened) continue;
        if (cn.closed || cn.shut || cn.desync) j.need_fresh_probe = true;
        judge_framing(i, cn, j);
        judge_unmatched(cn, j);
        judge_closed_on_piece(c, i, cn, j);
        judge_requests(c, i, cn, j);
    }
    j.consider(Shadow::check(j.shadow, options_.state));
    judge_side_probes(j);
    judge_flood(j);
    judge_target(c, j);
    Verdict& v = j.candidate;
    if (v)
        v.summary =
            v.culprit_fc >= 0
                ? fmt::format("{} [{} {}]", v.summary, class_name(c.cls),
                              codec::function_label(static_cast<std::uint8_t>(v.culprit_fc)))
                : fmt::format("{} [{}]", v.summary, class_name(c.cls));
    out_.verdict = std::move(v);
}

void CaseRunner::side_probe() {
    const std::int64_t t0 = net::now_ns();
    // What the case's connections are in the middle of, for the rule.
    std::string during = kRequestHeld;
    for (const Conn& cn : conns_) {
        if (!cn.opened || cn.closed) continue;
        if (!cn.desync && cn.sent.size() > cn.parsed) during = kPartialFrameCulprit;
        for (const Pending& pd : cn.pending)
            if (pd.answered_ns && pd.rsp_size > lim::kMbapHeader &&
                (received_frames(cn)[pd.rsp_offset + lim::kMbapHeader] & codec::kExceptionBit) &&
                during != kPartialFrameCulprit)
                during = kExceptionHeld;
    }
    const ProbeResult r = probe_target(target_, profile_, options_.timeout_ms);
    const std::int64_t ms = (net::now_ns() - t0) / net::kNsPerMs;
    event(kFreshConn, TraceKind::FreshProbe, {},
          fmt::format("concurrent probe: {} after {} ms", probe_result_name(r), ms));
    side_probes_.push_back(SideProbe{r, ms, std::move(during)});
}

// A piece the target's program leaves unread this long is left to join the next one: a
// server may wait for a whole header before it reads (and the campaign must go on).
constexpr std::int64_t kPieceReadWaitMs = 200;

void CaseRunner::await_read_by_target(std::uint8_t index) {
    if (index >= conns_.size()) return;
    Conn& c = conns_[index];
    if (!c.link || c.closed || c.sent.empty()) return;
    const bool read = wait_for_target_read(index);
    // Reading is not yet acting: a patient run gives the target a moment to act on the piece
    // (a close that comes after the next piece went out is not told apart from a close on
    // the whole).
    if (read && !c.closed && options_.piece_settle_ms > 0)
        pump(net::now_ns() + options_.piece_settle_ms * net::kNsPerMs, [&] { return c.closed; });
    if (c.closed && !c.shut && !c.desync && c.sent.size() > c.parsed)
        c.closed_on_piece = c.sent.size() - c.parsed;
}

bool CaseRunner::wait_for_target_read(std::uint8_t index) {
    Conn& c = conns_[index];
    const std::int64_t deadline = net::now_ns() + kPieceReadWaitMs * net::kNsPerMs;
    int pause_us = 10;
    for (;;) {
        const std::int64_t unread = c.link->unread_by_target();
        if (unread == 0) return true;
        if (unread < 0) return false;  // not knowable (another host): the gap alone
        if (net::now_ns() >= deadline) {
            event(index, TraceKind::LeftUnread, {},
                  fmt::format("the target left {} byte(s) unread for {} ms: the next piece "
                              "may join them",
                              unread, kPieceReadWaitMs));
            return false;
        }
        // A target reads within microseconds when it is running: check again soon, less
        // often the longer it takes.
        ::usleep(static_cast<useconds_t>(pause_us));
        pause_us = std::min(pause_us * 2, 1000);
        read_conn(index);
        if (c.closed) return true;
    }
}

Execution CaseRunner::run(const Case& c) {
    // A process that exited before the case began was killed by something before it.
    if (options_.process_exited && options_.process_exited()) {
        out_.down_before = true;
        return std::move(out_);
    }
    conns_.resize(std::max<std::size_t>(c.connections(), 1));
    for (const Step& s : c.steps) {
        perform(s);
        if (out_.down_before) return std::move(out_);
    }
    await_answers_before_probes();
    close_out();
    if (!await_close_out()) event(0, TraceKind::Timeout);
    judge(c);
    for (const Conn& cn : conns_)
        for (const Pending& pd : cn.pending)
            if (pd.answered_ns && pd.sent_ns)  // (a frame cut by a silence has no send time)
                out_.slowest_answer_ns =
                    std::max(out_.slowest_answer_ns, pd.answered_ns - pd.sent_ns);
    return std::move(out_);
}

void CaseRunner::perform(const Step& s) {
    if (s.delay_us && s.op == Op::Send) await_read_by_target(s.conn);
    if (s.delay_us >= 2000) {
        const std::int64_t until = net::now_ns() + s.delay_us * 1000ll;
        pump(until, [] { return false; });
    } else if (s.delay_us) {
        // Short gaps: poll() rounds up to milliseconds, so sleep precisely instead.
        ::usleep(s.delay_us);
    }
    switch (s.op) {
        case Op::Send:
            send_bytes(s.conn, s.bytes);
            break;
        case Op::ShutdownWrite:
            if (ensure_open(s.conn) && !conns_[s.conn].closed && !conns_[s.conn].shut) {
                Conn& cn = conns_[s.conn];
                cn.link->shutdown_write();
                cn.shut = true;
                cn.shut_after_frames = !cn.desync && cn.parsed == cn.sent.size();
                event(s.conn, TraceKind::ShutdownWrite);
            }
            break;
        case Op::Await: {
            const Conn& cn = conns_[s.conn];
            pump(net::now_ns() + options_.timeout_ms * net::kNsPerMs, [&] { return answered(cn); });
            break;
        }
        case Op::Flood:
            flood(s.count);
            break;
        case Op::SideProbe:
            side_probe();
            break;
    }
}

// Close out each connection: an in-stream probe after intact streams (so that silence to the
// case's frames is told apart from a stalled connection), a half-close after desynchronised
// ones.
void CaseRunner::close_out() {
    for (std::size_t i = 0; i < conns_.size(); ++i) {
        Conn& cn = conns_[i];
        if (!cn.opened || !cn.link || cn.closed) continue;
        if (profile_.serial_line && profile_.framing == codec::Framing::Rtu) close_partial(cn);
        if (!cn.shut && !cn.desync && cn.parsed == cn.sent.size()) {
            send_closing_probe(static_cast<std::uint8_t>(i));
        } else {
            if (!cn.shut) {
                cn.link->shutdown_write();
                cn.shut = true;
                event(static_cast<std::uint8_t>(i), TraceKind::ShutdownWrite);
            }
        }
    }
}

void CaseRunner::send_closing_probe(std::uint8_t index) {
    Conn& cn = conns_[index];
    std::uint16_t tid = 0xFADE;
    while (std::any_of(cn.pending.begin(), cn.pending.end(),
                       [&](const Pending& p) { return p.tid == tid; }))
        ++tid;
    const std::size_t before = cn.pending.size();
    send_bytes(index, probe_frame(profile_, tid));
    if (cn.pending.size() > before) {
        cn.pending.back().probe = true;
        cn.pending.back().awaited_probe = profile_.drops_after_exception;
    }
}

// Waits until every connection answered its probe or closed after its half-close.
bool CaseRunner::await_close_out() {
    const std::int64_t deadline = net::now_ns() + options_.timeout_ms * net::kNsPerMs;
    return pump(deadline, [&] {
        for (const Conn& cn : conns_) {
            if (!cn.opened || !cn.link) continue;
            if (cn.shut_after_frames) {
                if (!cn.closed && !answered(cn)) return false;
            } else if ((cn.shut || cn.desync) ? !cn.closed : !answered(cn)) {
                return false;
            }
        }
        return true;
    });
}

}  // namespace

std::string_view trace_kind_name(TraceKind k) noexcept {
    const auto i = static_cast<std::size_t>(k);
    return i < kTraceNames.size() ? kTraceNames[i] : "unknown";
}

bool trace_kind_from_name(std::string_view name, TraceKind& out) noexcept {
    for (std::size_t i = 0; i < kTraceNames.size(); ++i) {
        if (kTraceNames[i] == name) {
            out = static_cast<TraceKind>(i);
            return true;
        }
    }
    return false;
}

std::string_view probe_result_name(ProbeResult r) noexcept {
    switch (r) {
        case ProbeResult::Ok:
            return "answered";
        case ProbeResult::ConnectFailed:
            return "connect failed";
        case ProbeResult::NoAnswer:
            return "no answer";
        case ProbeResult::Closed:
            return "closed";
        case ProbeResult::BadAnswer:
            return "bad answer";
    }
    return "unknown";
}

Verdict fresh_probe_verdict(ProbeResult r) {
    switch (r) {
        case ProbeResult::Ok:
            return {};
        case ProbeResult::ConnectFailed:
        case ProbeResult::Closed:
            return Verdict{Oracle::Crash,
                           kTargetDownRule,
                           -1,
                           r == ProbeResult::Closed ? "target closes every new connection"
                                                    : "target stopped accepting connections",
                           "the target accepts and serves a fresh connection",
                           std::string(probe_result_name(r))};
        case ProbeResult::NoAnswer:
        case ProbeResult::BadAnswer:
            break;
    }
    // The server as a whole no longer answers (not just one connection).
    return Verdict{
        Oracle::Hang,
        kWholeServerHangRule,
        -1,
        fmt::format("whole server hangs: a fresh connection's probe got {}", probe_result_name(r)),
        "an answer on a fresh connection",
        std::string(probe_result_name(r))};
}

int connect_with_timeout(const net::Endpoint& target, int timeout_ms) noexcept {
    const int fd = net::connect_nonblocking(target);
    if (fd < 0) return fd;
    pollfd p{fd, POLLOUT, 0};
    int rc;
    do {
        rc = ::poll(&p, 1, timeout_ms);
    } while (rc < 0 && errno == EINTR);
    int err = rc == 0 ? ETIMEDOUT : net::socket_error(fd);
    if (rc < 0) err = errno;
    if (err != 0) {
        ::close(fd);
        return -err;
    }
    net::set_nodelay(fd);
    return fd;
}

std::vector<std::uint8_t> probe_frame(const TargetProfile& profile, std::uint16_t tid) {
    return frame_pdu(profile.probe_pdu, tid, profile.unit, profile.framing);
}

ProbeResult probe_target(Connector& target, const TargetProfile& profile, int timeout_ms) {
    int error = 0;
    const std::unique_ptr<Link> link = target.open(timeout_ms, error);
    if (!link) return ProbeResult::ConnectFailed;
    const auto f = probe_frame(profile, 0x7E57);
    if (link->send(f.data(), f.size()) != static_cast<ssize_t>(f.size()))
        return ProbeResult::Closed;
    std::uint8_t buf[lim::kMaxTcpAdu];
    std::size_t have = 0;
    const std::int64_t deadline = net::now_ns() + timeout_ms * net::kNsPerMs;
    for (;;) {
        const std::int64_t left = deadline - net::now_ns();
        if (left <= 0) return ProbeResult::NoAnswer;
        if (!wait_readable(*link,
                           static_cast<int>(std::max<std::int64_t>(1, left / net::kNsPerMs))))
            continue;
        const ssize_t n = link->recv(buf + have, sizeof buf - have);
        if (n == 0) return ProbeResult::Closed;
        if (n < 0) {
            if (n == -EAGAIN) continue;
            return ProbeResult::Closed;
        }
        have += static_cast<std::size_t>(n);
        if (profile.framing != codec::Framing::Mbap) {
            WireFrame frame;
            const WireCut cut =
                cut_frame(codec::Bytes(buf, have), profile.framing, false, 0, frame);
            if (cut == WireCut::Lost || (cut == WireCut::Frame && !frame.discard.empty()))
                return ProbeResult::BadAnswer;
            if (cut == WireCut::Frame) return ProbeResult::Ok;
        } else if (have >= lim::kMbapHeader) {
            const codec::MbapHeader h = codec::read_mbap_header(buf);
            if (h.length < 2 || h.length > lim::kMaxMbapLength) return ProbeResult::BadAnswer;
            if (have >= codec::adu_size(h)) return ProbeResult::Ok;
        }
        if (have == sizeof buf) return ProbeResult::BadAnswer;
    }
}

Execution execute_case(const Case& c, Connector& target, const TargetProfile& profile,
                       const ExecOptions& options) {
    if (is_cross_transport(c.cls)) return execute_cross_transport(c, target, profile, options);
    CaseRunner r(target, profile, options);
    return r.run(c);
}

}  // namespace mbstorm::netfuzz
