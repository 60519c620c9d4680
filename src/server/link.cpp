// The served connection's link (link.hpp): its framing of answers and its TLS session. A TLS
// link runs the server's half of the handshake over memory BIOs, looks up the client's role,
// encrypts the output queue's head just before it is sent and may hand the record layer to the
// kernel once established.
#include "server/link.hpp"

#include <cerrno>

#include "codec/rtu.hpp"

namespace mbstorm::server {

struct Link::Tls {
    explicit Tls(const std::shared_ptr<net::TlsContext>& ctx) : session(ctx) {
        cipher_out.reserve(4096);
    }
    bool has_output() const noexcept {
        return cipher_sent < cipher_out.size() || session.pending_output() > 0;
    }

    net::TlsSession session;
    std::vector<std::uint8_t> cipher_out;  // ciphertext being sent, from cipher_sent on
    std::size_t cipher_sent = 0;
    // Plaintext bytes at the head of the connection's output queue that cipher_out carries:
    // they leave the queue once all of cipher_out has been sent.
    std::size_t plain_carried = 0;
    const TlsRoles* roles = nullptr;
    // The worker's plaintext buffer while next_request() reads this input (take_tls).
    std::vector<std::uint8_t>* scratch = nullptr;
    // The kernel's TLS carries the records (ktls_offload.hpp): plaintext both ways from here
    // on; the session stays for the role and is never used again.
    bool kernel = false;
    bool stays_in_userspace = false;  // the hand-off was refused for good, or not wanted
};

Link::Link() = default;
Link::Link(Link&&) noexcept = default;
Link& Link::operator=(Link&&) noexcept = default;
Link::~Link() = default;

bool Link::accepted(Kind kind, const std::shared_ptr<net::TlsContext>& tls, const TlsRoles* roles,
                    bool offload) {
    kind_ = kind;
    bytes_pass_through_ = kind != Kind::Tls;
    allowed_ = nullptr;
    mbap_.reset();
    if (kind_ == Kind::Rtu) {
        if (!rtu_)
            rtu_ = std::make_unique<codec::RtuSplitter>(codec::RtuSplitter::Direction::Requests,
                                                        /*skip_bad_crc=*/true);
        rtu_->reset();
    }
    if (kind_ != Kind::Tls) return true;
    try {
        tls_ = std::make_unique<Tls>(tls);
        tls_->roles = roles;
        tls_->stays_in_userspace = !offload;
        if (offload) tls_->session.track_for_offload();
    } catch (...) {
        tls_.reset();
    }
    if (!tls_ || !tls_->session.valid()) {
        tls_.reset();
        return false;
    }
    return true;
}

void Link::released() noexcept {
    mbap_.reset();
    tls_.reset();
    allowed_ = nullptr;
}

Link::Handshake Link::step_handshake(codec::Bytes received) {
    Tls& t = *tls_;
    t.session.feed(received.data(), received.size());
    if (t.session.established()) return Handshake::Done;
    const net::TlsStatus hs = t.session.handshake();
    if (hs == net::TlsStatus::WantMore) return Handshake::Going;
    if (hs != net::TlsStatus::Ok) return Handshake::Failed;
    allowed_ = t.roles != nullptr ? t.roles->allowed_for(t.session.peer_role()) : nullptr;
    return Handshake::SetUp;
}

LinkInput Link::take_tls(codec::Bytes received, std::vector<std::uint8_t>& scratch, bool& set_up) {
    switch (step_handshake(received)) {
        case Handshake::Going:
            return LinkInput::SettingUp;
        case Handshake::Failed:
            return LinkInput::SetUpFailed;
        case Handshake::SetUp:
            set_up = true;
            break;
        case Handshake::Done:
            break;
    }
    tls_->scratch = &scratch;
    return LinkInput::Drained;
}

bool Link::next_request_rest(codec::TcpFrame& frame, LinkInput& end, std::uint64_t& discarded,
                             std::uint64_t& crc_skipped) noexcept {
    end = LinkInput::Drained;
    if (kind_ == Kind::Rtu) {
        for (;;) {
            switch (rtu_->next(frame)) {
                case codec::RtuSplitter::Status::Frame:
                    return true;
                case codec::RtuSplitter::Status::Skipped:  // dropped, as a serial slave does
                    ++crc_skipped;
                    continue;
                case codec::RtuSplitter::Status::NeedMore:
                    return false;
                case codec::RtuSplitter::Status::Fatal:
                    // No length rule to resynchronise on: the frames before it are answered
                    // and the connection closes after that.
                    end = rtu_->error() == codec::CodecError::BadCrc ? LinkInput::BadCrc
                                                                     : LinkInput::FramingLost;
                    return false;
            }
        }
    }
    if (bytes_pass_through_) return false;  // the kernel's TLS: the splitter had it all
    // TLS in userspace: the next record's plaintext, split like plain MBAP (back here when it
    // holds no more whole requests, until no plaintext is left).
    const std::size_t n = read_plain(*tls_->scratch, end);
    if (n == 0) return false;
    mbap_.feed(codec::Bytes(tls_->scratch->data(), n));
    return next_request(frame, end, discarded, crc_skipped);
}

std::size_t Link::read_plain(std::vector<std::uint8_t>& scratch, LinkInput& end) {
    std::size_t n = 0;
    const net::TlsStatus st = tls_->session.read(scratch.data(), scratch.size(), n);
    if (n > 0) return n;
    if (st == net::TlsStatus::Closed) end = LinkInput::PeerClosed;
    if (st == net::TlsStatus::Failed) end = LinkInput::PeerFailed;
    return 0;
}

bool Link::record_partly_in() const noexcept {
    return !bytes_pass_through_ && tls_ && tls_->session.partial_input();
}

bool Link::setting_up() const noexcept {
    return kind_ == Kind::Tls && tls_ && !tls_->session.established();
}

std::size_t Link::frame_answer(std::uint8_t* p, const codec::TcpFrame& request,
                               std::size_t pdu_size) const noexcept {
    if (kind_ == Kind::Rtu) {
        p[0] = request.header.unit_id;
        return codec::append_rtu_crc(p, 1 + pdu_size);
    }
    codec::write_mbap_header(p, request.header.transaction_id, request.header.unit_id, pdu_size);
    return codec::limits::kMbapHeader + pdu_size;
}

std::size_t Link::write_exception(std::uint8_t* p, const codec::TcpFrame& request,
                                  codec::ExceptionCode code) const noexcept {
    if (kind_ == Kind::Rtu) {
        codec::write_rtu_exception(p, request.header.unit_id,
                                   request.pdu.empty() ? 0 : request.pdu[0],
                                   static_cast<std::uint8_t>(code));
        return codec::kRtuExceptionAduSize;
    }
    codec::write_exception_frame(p, request, code);
    return codec::kExceptionAduSize;
}

bool Link::outgoing_tls(const std::uint8_t* queued, std::size_t size, codec::Bytes& wire) {
    Tls& t = *tls_;
    if (t.cipher_sent == t.cipher_out.size()) {
        t.cipher_out.clear();
        t.cipher_sent = 0;
        if (t.session.established() && t.plain_carried == 0 && queued != nullptr && size > 0) {
            if (t.session.write(queued, size) != net::TlsStatus::Ok) return false;
            t.plain_carried = size;
        }
        try {
            t.session.take_output(t.cipher_out);
        } catch (...) {
            return false;
        }
    }
    wire = codec::Bytes(t.cipher_out.data() + t.cipher_sent, t.cipher_out.size() - t.cipher_sent);
    return true;
}

std::size_t Link::sent_tls(std::size_t n) noexcept {
    Tls& t = *tls_;
    t.cipher_sent += n;
    if (t.cipher_sent < t.cipher_out.size()) return 0;
    const std::size_t plain = t.plain_carried;
    t.plain_carried = 0;
    return plain;
}

bool Link::has_own_output() const noexcept {
    return !bytes_pass_through_ && tls_->has_output();
}

bool Link::is_record_layer_error(int result) const noexcept {
    return result == -EIO && kind_ == Kind::Tls && tls_ && tls_->kernel;
}

bool Link::may_hand_off() const noexcept {
    return kind_ == Kind::Tls && tls_ && !tls_->kernel && !tls_->stays_in_userspace &&
           !tls_->has_output() && tls_->plain_carried == 0;
}

net::KtlsHandOffResult Link::hand_off(int fd, bool real_fd) noexcept {
    Tls& t = *tls_;
    const net::KtlsHandOffResult handed = net::ktls_hand_off(t.session, fd, real_fd);
    if (handed == net::KtlsHandOffResult::Done) t.kernel = bytes_pass_through_ = true;
    if (handed == net::KtlsHandOffResult::Userspace || handed == net::KtlsHandOffResult::Broken)
        t.stays_in_userspace = true;
    return handed;
}

bool Link::resumed() const noexcept {
    return kind_ == Kind::Tls && tls_ && tls_->session.resumed();
}

}  // namespace mbstorm::server
