#include "netfuzz/cross_transport.hpp"

#include <fmt/format.h>
#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <string>

#include "codec/limits.hpp"
#include "codec/mbap.hpp"
#include "net/clock.hpp"
#include "net/tls_hello.hpp"
#include "netfuzz/rules.hpp"
#include "netfuzz/tls_link.hpp"

namespace mbstorm::netfuzz {
namespace {

namespace lim = codec::limits;
using Bytes = std::vector<std::uint8_t>;
constexpr std::uint8_t kProbeConn = 255;  // as the executor names its fresh probes
constexpr std::int64_t kStallMs = 250;    // as the executor's stall oracle

Case one_case(MutationClass cls, std::uint8_t function) {
    Case c;
    c.cls = cls;
    c.function = function;
    return c;
}

// Sends `bytes`, then probes on another connection while the foreign one is held open.
void send_then_probe(Case& c, Bytes bytes) {
    c.steps.push_back(Step{Op::Send, 0, 0, 0, std::move(bytes)});
    c.steps.push_back(Step{Op::SideProbe, 0, 0, 0, {}});
}

// TLS records a client might send after its ClientHello: ChangeCipherSpec, then an
// application-data record (what a request looks like encrypted).
Bytes tls_records_after_hello() {
    // one-place: TLS record headers (ChangeCipherSpec 0x14, application data 0x17), no Modbus.
    Bytes b = {0x14, 0x03, 0x03, 0x00, 0x01, 0x01, 0x17, 0x03, 0x03, 0x00, 0x20};
    for (std::uint8_t i = 0; i < 0x20; ++i) b.push_back(static_cast<std::uint8_t>(i * 37 + 11));
    return b;
}

class CrossRunner {
  public:
    CrossRunner(Connector& target, const TargetProfile& profile, const ExecOptions& options)
        : target_(target), profile_(profile), options_(options), start_(net::now_ns()) {}
    Execution run(const Case& c);

  private:
    void event(std::uint8_t conn, TraceKind kind, Bytes bytes = {}, std::string note = {}) {
        out_.trace.push_back(TraceEvent{(net::now_ns() - start_) / 1000, conn, kind,
                                        std::move(bytes), std::move(note)});
    }
    bool open(MutationClass cls);
    void send(const Bytes& bytes);
    void read_available();
    void side_probe();
    void judge(const Case& c);
    Verdict answered_verdict(MutationClass cls) const;

    Connector& target_;
    const TargetProfile& profile_;
    ExecOptions options_;
    std::int64_t start_;
    std::unique_ptr<Link> link_;
    TlsLink* session_ = nullptr;  // set when the bytes go beside an established session
    bool closed_ = false, shut_ = false;
    Bytes sent_, received_;
    struct Probe {
        ProbeResult result;
        std::int64_t ms;
    };
    std::vector<Probe> side_probes_;
    Execution out_;
};

bool CrossRunner::open(MutationClass cls) {
    auto* tls = dynamic_cast<TlsConnector*>(&target_);
    int error = 0;
    if (cls == MutationClass::TlsToPlain) {
        if (tls != nullptr) {
            event(0, TraceKind::ConnectFailed, {}, "a tls-to-plain case needs a plain target");
            return false;
        }
        link_ = target_.open(options_.timeout_ms, error);
    } else if (tls == nullptr) {
        event(0, TraceKind::ConnectFailed, {},
              fmt::format("a {} case needs --transport tls", class_name(cls)));
        return false;
    } else if (cls == MutationClass::PlaintextToTls) {
        link_ = tls->open_plain(options_.timeout_ms, error);
    } else {
        link_ = tls->open(options_.timeout_ms, error);
        session_ = dynamic_cast<TlsLink*>(link_.get());
    }
    if (!link_) {
        event(0, TraceKind::ConnectFailed, {}, std::strerror(error));
        out_.down_before = true;
        return false;
    }
    event(0, TraceKind::Connect, {}, session_ ? std::string("TLS session established") : "");
    return true;
}

void CrossRunner::send(const Bytes& bytes) {
    if (closed_ || shut_) return;
    std::size_t done = 0;
    if (session_ != nullptr) {
        const ssize_t n =
            session_->send_beside_session(bytes.data(), bytes.size(), options_.timeout_ms);
        done = n > 0 ? static_cast<std::size_t>(n) : 0;
        if (n < 0 && n != -EAGAIN) {
            closed_ = true;
            event(0, TraceKind::Reset, {}, std::strerror(static_cast<int>(-n)));
        }
    } else {
        const std::int64_t deadline = net::now_ns() + options_.timeout_ms * net::kNsPerMs;
        while (done < bytes.size() && net::now_ns() < deadline) {
            const ssize_t n = link_->send(bytes.data() + done, bytes.size() - done);
            if (n > 0) {
                done += static_cast<std::size_t>(n);
            } else if (n == -EAGAIN || n == 0) {
                read_available();
                pollfd p{link_->poll_fd(), POLLOUT, 0};
                ::poll(&p, 1, 10);
            } else {
                closed_ = true;
                event(0, TraceKind::Reset, {}, std::strerror(static_cast<int>(-n)));
                break;
            }
        }
    }
    if (done == 0) return;
    event(0, TraceKind::Send, Bytes(bytes.begin(), bytes.begin() + static_cast<long>(done)),
          session_ ? std::string("beside the TLS session") : "");
    sent_.insert(sent_.end(), bytes.begin(), bytes.begin() + static_cast<long>(done));
}

void CrossRunner::read_available() {
    std::uint8_t buf[4096];
    while (!closed_) {
        const ssize_t n = link_->recv(buf, sizeof buf);
        if (n > 0) {
            event(0, TraceKind::Recv, Bytes(buf, buf + n));
            received_.insert(received_.end(), buf, buf + n);
        } else if (n == 0) {
            closed_ = true;
            event(0, TraceKind::PeerClosed);
        } else {
            if (n != -EAGAIN) {
                closed_ = true;
                event(0, TraceKind::Reset, {}, std::strerror(static_cast<int>(-n)));
            }
            return;
        }
    }
}

void CrossRunner::side_probe() {
    read_available();
    const std::int64_t t0 = net::now_ns();
    const ProbeResult r = probe_target(target_, profile_, options_.timeout_ms);
    const std::int64_t ms = (net::now_ns() - t0) / net::kNsPerMs;
    event(kProbeConn, TraceKind::FreshProbe, {},
          fmt::format("concurrent probe: {} after {} ms", probe_result_name(r), ms));
    side_probes_.push_back(Probe{r, ms});
}

// The transaction ids of the MBAP frames the case sent (for TLS bytes, what the first two
// bytes would be taken for), and whether a frame that came back carries one of them.
Verdict CrossRunner::answered_verdict(MutationClass cls) const {
    std::vector<std::uint16_t> tids;
    int fc = -1;
    if (cls == MutationClass::TlsToPlain) {
        if (sent_.size() >= 2) tids.push_back(codec::load_be16(sent_.data()));
    } else {
        for (std::size_t off = 0; sent_.size() - off >= lim::kMbapHeader + 1;) {
            const std::size_t size = codec::announced_adu_size(sent_.data() + off);
            tids.push_back(codec::load_be16(sent_.data() + off));
            if (fc < 0) fc = sent_[off + lim::kMbapHeader];
            if (size <= lim::kMbapHeader || size > sent_.size() - off) break;
            off += size;
        }
    }
    for (std::size_t off = 0; received_.size() - off >= lim::kMbapHeader + 1;) {
        const codec::MbapHeader h = codec::read_mbap_header(received_.data() + off);
        if (h.length < 2 || h.length > lim::kMaxMbapLength) break;
        const std::size_t size = codec::adu_size(h);
        if (size > received_.size() - off) break;
        if (std::find(tids.begin(), tids.end(), h.transaction_id) != tids.end()) {
            const std::string seen = hex(codec::Bytes(received_.data() + off, size));
            // A TLS record's minor version byte (1 to 4) is the high byte of the protocol id
            // its bytes read as: answering them is answering a frame a conforming server
            // discards, whatever else it misreads.
            if (cls == MutationClass::TlsToPlain)
                return Verdict{Oracle::SpecDeviation,
                               kAnswersNonzeroProtocolIdRule,
                               -1,
                               "the plain Modbus/TCP port answered the bytes of a TLS "
                               "ClientHello as a Modbus request (their protocol id is not 0)",
                               "no answer: the bytes are no Modbus/TCP frame (protocol id != 0); "
                               "the connection closed or ignored",
                               seen};
            const bool in_session = cls == MutationClass::PlaintextInSession;
            return Verdict{
                Oracle::SpecDeviation,
                in_session ? kTlsSessionAnswersPlaintextRule : kTlsPortAnswersPlaintextRule,
                fc,
                in_session ? "plain Modbus/TCP written between the records of a TLS session was "
                             "answered: the session does not protect the requests"
                           : "the TLS port answered plain Modbus/TCP: a client without a "
                             "certificate is served",
                "no Modbus answer: the connection refused (a TLS alert at most) and closed",
                seen};
        }
        off += size;
    }
    return {};
}

void CrossRunner::judge(const Case& c) {
    Verdict candidate;
    auto consider = [&](Verdict v) {
        if (v && (!candidate || v.oracle < candidate.oracle)) candidate = std::move(v);
    };
    consider(answered_verdict(c.cls));
    const std::int64_t stall_ms = std::min<std::int64_t>(kStallMs, options_.timeout_ms);
    for (const Probe& p : side_probes_) {
        if (p.result == ProbeResult::ConnectFailed) continue;  // the fresh probe judges that
        if (p.result == ProbeResult::Ok && p.ms < stall_ms) continue;
        // To a plain Modbus/TCP server, TLS bytes are a frame that never finishes: a stall
        // they cause is the one a started frame causes.
        const std::string_view held =
            c.cls == MutationClass::TlsToPlain ? kPartialFrameCulprit : class_name(c.cls);
        consider(Verdict{
            Oracle::Hang, stalls_other_connections_rule(held), -1,
            fmt::format(
                "a concurrent connection {} ({} ms) while another held {}",
                p.result == ProbeResult::Ok ? std::string("was answered late")
                                            : fmt::format("got {}", probe_result_name(p.result)),
                p.ms, c.cls == MutationClass::TlsToPlain ? "TLS bytes" : "plain Modbus/TCP"),
            fmt::format("an answer within {} ms, whatever other connections send", stall_ms),
            fmt::format("{} after {} ms", probe_result_name(p.result), p.ms)});
    }
    ProbeResult r = probe_target(target_, profile_, options_.timeout_ms);
    event(kProbeConn, TraceKind::FreshProbe, {}, std::string(probe_result_name(r)));
    if (r == ProbeResult::Closed || r == ProbeResult::ConnectFailed) {
        // A busy target may let a connect wait out its backlog: look again before calling
        // it a crash (as the executor does).
        ::usleep(r == ProbeResult::Closed ? 50000 : 200000);
        r = probe_target(target_, profile_, options_.timeout_ms);
        event(kProbeConn, TraceKind::FreshProbe, {}, std::string(probe_result_name(r)));
    }
    if (r != ProbeResult::Ok) {
        out_.target_down = r == ProbeResult::ConnectFailed || r == ProbeResult::Closed;
        Verdict v = fresh_probe_verdict(r);
        v.rule = rule_with_culprit(v.rule, class_name(c.cls));
        consider(std::move(v));
    }
    if (candidate) candidate.summary += fmt::format(" [{}]", class_name(c.cls));
    out_.verdict = std::move(candidate);
}

Execution CrossRunner::run(const Case& c) {
    if (!open(c.cls)) return std::move(out_);
    for (const Step& s : c.steps) {
        if (s.delay_us) ::usleep(s.delay_us);
        switch (s.op) {
            case Op::Send:
                send(s.bytes);
                break;
            case Op::SideProbe:
                side_probe();
                break;
            case Op::ShutdownWrite:
                if (!closed_ && !shut_) {
                    link_->shutdown_write();
                    shut_ = true;
                    event(0, TraceKind::ShutdownWrite);
                }
                break;
            case Op::Await:
            case Op::Flood:
                break;
        }
    }
    // The server may be waiting for the rest of what it took for a record or a frame: the
    // half-close tells it there is none.
    read_available();
    if (!closed_ && !shut_) {
        link_->shutdown_write();
        shut_ = true;
        event(0, TraceKind::ShutdownWrite);
    }
    const std::int64_t deadline = net::now_ns() + options_.timeout_ms * net::kNsPerMs;
    while (!closed_ && net::now_ns() < deadline) {
        const auto left_ms = std::max<std::int64_t>(1, (deadline - net::now_ns()) / net::kNsPerMs);
        if (wait_readable(*link_, static_cast<int>(left_ms))) read_available();
    }
    if (!closed_) event(0, TraceKind::Timeout, {}, "the connection stayed open");
    link_.reset();
    judge(c);
    return std::move(out_);
}

}  // namespace

bool is_cross_transport(MutationClass c) noexcept {
    return c == MutationClass::PlaintextToTls || c == MutationClass::PlaintextInSession ||
           c == MutationClass::TlsToPlain;
}

std::vector<Case> cross_transport_cases(const Connector& target, const TargetProfile& profile) {
    std::vector<Case> out;
    if (profile.probe_pdu.empty()) return out;
    const std::uint8_t fc = profile.probe_pdu[0];
    if (dynamic_cast<const TlsConnector*>(&target) != nullptr) {
        // The request a client without TLS would send, then the same with transaction ids
        // whose bytes read as the header of each TLS record type (ChangeCipherSpec, alert,
        // handshake, application data, version 3.x): the record layer must refuse them too.
        for (std::uint16_t tid : {0x0F01, 0x1403, 0x1503, 0x1603, 0x1703}) {
            Case c = one_case(MutationClass::PlaintextToTls, fc);
            send_then_probe(c, frame_pdu(profile.probe_pdu, tid, profile.unit));
            out.push_back(std::move(c));
        }
        // Three bytes of a request, held: a record header is five; others must not wait.
        Case held = one_case(MutationClass::PlaintextToTls, fc);
        Bytes whole = frame_pdu(profile.probe_pdu, 0x1603, profile.unit);
        send_then_probe(held, Bytes(whole.begin(), whole.begin() + 3));
        held.steps.push_back(Step{Op::Send, 0, 0, 0, Bytes(whole.begin() + 3, whole.end())});
        out.push_back(std::move(held));
        // Plaintext inside an established session: the record layer must not take it.
        Case inside = one_case(MutationClass::PlaintextInSession, fc);
        send_then_probe(inside, frame_pdu(profile.probe_pdu, 0x0F02, profile.unit));
        out.push_back(std::move(inside));
        return out;
    }
    // A plain Modbus/TCP port only: an RTU-over-TCP port has a framing of its own.
    if (dynamic_cast<const TcpConnector*>(&target) == nullptr ||
        target.framing() != codec::Framing::Mbap)
        return out;
    // TLS where plain Modbus/TCP is spoken: ClientHellos (TLS 1.3 and 1.2), one held after its
    // record header, and one followed by the records a session goes on with.
    for (const bool tls12 : {false, true}) {
        Bytes hello = net::tls_client_hello(tls12);
        if (hello.size() <= 5) return out;
        Case c = one_case(MutationClass::TlsToPlain, 0);
        send_then_probe(c, hello);
        out.push_back(std::move(c));
        if (tls12) continue;
        Case held = one_case(MutationClass::TlsToPlain, 0);
        send_then_probe(held, Bytes(hello.begin(), hello.begin() + 5));
        held.steps.push_back(Step{Op::Send, 0, 0, 0, Bytes(hello.begin() + 5, hello.end())});
        out.push_back(std::move(held));
        Case session = one_case(MutationClass::TlsToPlain, 0);
        Bytes flight = hello;
        const Bytes more = tls_records_after_hello();
        flight.insert(flight.end(), more.begin(), more.end());
        send_then_probe(session, std::move(flight));
        out.push_back(std::move(session));
    }
    return out;
}

Execution execute_cross_transport(const Case& c, Connector& target, const TargetProfile& profile,
                                  const ExecOptions& options) {
    CrossRunner r(target, profile, options);
    return r.run(c);
}

}  // namespace mbstorm::netfuzz
