// The load connection's link (link.hpp): its set-up and TLS session. Plain MBAP and RTU links
// need no set-up; a TLS link runs its handshake over memory BIOs, encrypts each flush's queued
// requests into records and may hand the record layer to the kernel once established.
#include "load/link.hpp"

#include <algorithm>
#include <cerrno>

namespace mbstorm::load {

struct Link::Tls {
    explicit Tls(std::shared_ptr<net::TlsContext> context, bool resume_sessions)
        : ctx(std::move(context)), resume(resume_sessions) {
        cipher.reserve(4096);
    }
    ~Tls() {
        if (saved != nullptr) net::free_tls_session(saved);
    }
    Tls(const Tls&) = delete;
    Tls& operator=(const Tls&) = delete;

    std::shared_ptr<net::TlsContext> ctx;
    bool resume;
    std::optional<net::TlsSession> session;  // one per TCP connection
    std::vector<std::uint8_t> cipher;        // ciphertext of the send in flight
    SSL_SESSION* saved = nullptr;            // resume: offered on the next connect
    // The kernel's TLS carries this connection's records (ktls_offload.hpp): plaintext both
    // ways from here on; the session stays only to be resumed.
    bool kernel = false;
    bool stays_in_userspace = false;  // the hand-off was refused for good, or not wanted
    std::int64_t set_up_started_ns = 0;
    std::uint64_t set_up_ns = 0;
    bool carried_data = false;  // over all its connections
    std::string error;
};

Link::Link(Kind kind, std::shared_ptr<net::TlsContext> tls, bool resume)
    : kind_(kind), bytes_pass_through_(kind != Kind::Tls) {
    if (kind_ == Kind::Rtu)
        rtu_ = std::make_unique<codec::RtuSplitter>(codec::RtuSplitter::Direction::Responses);
    if (kind_ == Kind::Tls) tls_ = std::make_unique<Tls>(std::move(tls), resume);
}

Link::Link(Link&&) noexcept = default;
Link& Link::operator=(Link&&) noexcept = default;
Link::~Link() = default;

LinkStart Link::connected(std::int64_t now, bool offload) {
    mbap_.reset();
    if (rtu_) rtu_->reset();
    if (kind_ != Kind::Tls) return LinkStart::Open;
    Tls& t = *tls_;
    t.session.reset();
    t.session.emplace(t.ctx, t.resume ? t.saved : nullptr);
    if (!t.session->valid()) {
        t.error = t.session->error();
        return LinkStart::SetUpFailed;
    }
    t.kernel = false;
    bytes_pass_through_ = false;
    t.stays_in_userspace = !offload;
    if (offload) {
        try {
            t.session->track_for_offload();
        } catch (...) {
            t.stays_in_userspace = true;  // no memory for the tracker: OpenSSL keeps the records
        }
    }
    t.set_up_started_ns = now;
    t.session->handshake();  // the ClientHello
    return LinkStart::SettingUp;
}

void Link::closed() noexcept {
    mbap_.reset();
    if (rtu_) rtu_->reset();
    if (kind_ != Kind::Tls || !tls_->session) return;
    Tls& t = *tls_;
    if (t.resume && t.session->established()) {
        if (SSL_SESSION* s = t.session->saved_session()) {
            if (t.saved != nullptr) net::free_tls_session(t.saved);
            t.saved = s;
        }
    }
    t.session.reset();  // the ciphertext buffer stays: a send from it may still be in flight
}

bool Link::set_up_overdue(std::int64_t now, std::int64_t timeout_ns) const noexcept {
    return kind_ == Kind::Tls && now - tls_->set_up_started_ns >= timeout_ns;
}

bool Link::next_rtu_answer(codec::TcpFrame& frame, LinkInput& end) noexcept {
    switch (rtu_->next(frame)) {
        case codec::RtuSplitter::Status::Frame:
            frame.header.transaction_id = rtu_transaction_;
            return true;
        case codec::RtuSplitter::Status::NeedMore:
            end = LinkInput::Answers;
            return false;
        case codec::RtuSplitter::Status::Skipped:  // not asked for here: an answer with a bad
            end = LinkInput::BadCrc;               // CRC is an error of the target's
            return false;
        case codec::RtuSplitter::Status::Fatal:
            end = rtu_->error() == codec::CodecError::BadCrc ? LinkInput::BadCrc
                                                             : LinkInput::FramingLost;
            return false;
    }
    return false;
}

LinkInput Link::open_tls(codec::Bytes received, std::int64_t now,
                         std::vector<std::uint8_t>& scratch, codec::Bytes& plain) {
    Tls& t = *tls_;
    if (t.kernel) {  // the kernel decrypted them
        plain = received;
        return LinkInput::Answers;
    }
    net::TlsSession& session = *t.session;
    session.feed(received.data(), received.size());
    LinkInput done = LinkInput::Answers;
    if (!session.established()) {
        const net::TlsStatus hs = session.handshake();
        if (hs == net::TlsStatus::WantMore) return LinkInput::SettingUp;
        if (hs != net::TlsStatus::Ok) {
            t.error = session.error();
            return LinkInput::SetUpFailed;
        }
        t.set_up_ns =
            static_cast<std::uint64_t>(std::max<std::int64_t>(now - t.set_up_started_ns, 0));
        done = LinkInput::SetUp;
    }
    std::size_t size = 0;
    for (;;) {
        std::size_t n = 0;
        const net::TlsStatus st = session.read(scratch.data() + size, scratch.size() - size, n);
        size += n;
        if (n > 0 && size < scratch.size()) continue;
        if (st == net::TlsStatus::Failed) {
            t.error = session.error();
            return LinkInput::PeerFailed;
        }
        if (st == net::TlsStatus::Closed) return LinkInput::PeerClosed;
        break;
    }
    if (size > 0) t.carried_data = true;
    plain = codec::Bytes(scratch.data(), size);
    return done;
}

bool Link::seal_tls(const std::uint8_t* queued, std::size_t size, codec::Bytes& wire) noexcept {
    if (!tls_->session || tls_->session->write(queued, size) != net::TlsStatus::Ok) return false;
    wire = take_tls_output();
    return true;
}

codec::Bytes Link::take_tls_output() noexcept {
    Tls& t = *tls_;
    if (!t.session || t.session->pending_output() == 0) return {};
    t.cipher.clear();
    try {
        t.session->take_output(t.cipher);
    } catch (...) {
        return {};  // no memory: the connection times out like any that stops answering
    }
    return codec::Bytes(t.cipher.data(), t.cipher.size());
}

bool Link::is_record_layer_error(int result) const noexcept {
    return result == -EIO && kind_ == Kind::Tls && tls_->kernel;
}

bool Link::may_hand_off() const noexcept {
    return kind_ == Kind::Tls && !tls_->kernel && !tls_->stays_in_userspace && tls_->session &&
           tls_->session->established();
}

net::KtlsHandOffResult Link::hand_off(int fd, bool real_fd) noexcept {
    Tls& t = *tls_;
    const net::KtlsHandOffResult handed = net::ktls_hand_off(*t.session, fd, real_fd);
    if (handed == net::KtlsHandOffResult::Done) t.kernel = bytes_pass_through_ = true;
    if (handed == net::KtlsHandOffResult::Userspace || handed == net::KtlsHandOffResult::Broken)
        t.stays_in_userspace = true;
    return handed;
}

std::uint64_t Link::set_up_ns() const noexcept {
    return kind_ == Kind::Tls ? tls_->set_up_ns : 0;
}

bool Link::carried_data() const noexcept {
    return kind_ == Kind::Tls && tls_->carried_data;
}

const std::string& Link::error() const noexcept {
    static const std::string none;
    return kind_ == Kind::Tls ? tls_->error : none;
}

bool Link::resumed() const noexcept {
    return kind_ == Kind::Tls && tls_->session && tls_->session->resumed();
}

}  // namespace mbstorm::load
