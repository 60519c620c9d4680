#include "netfuzz/tls_link.hpp"

#include <openssl/ssl.h>
#include <poll.h>
#include <sys/socket.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "net/clock.hpp"
#include "net/peer_queue.hpp"
#include "netfuzz/executor.hpp"

namespace mbstorm::netfuzz {
namespace {

// How long send() waits for the socket to take the rest of a request's ciphertext before it
// leaves it for the next call: a request left unsent would look like a target that is silent.
constexpr int kSendDrainMs = 100;

// Waits until `fd` is ready for `events` or `deadline_ns` passes. False on timeout.
bool wait_for(int fd, short events, std::int64_t deadline_ns) noexcept {
    for (;;) {
        const std::int64_t left_ms = (deadline_ns - net::now_ns()) / net::kNsPerMs;
        if (left_ms <= 0) return false;
        pollfd p{fd, events, 0};
        const int rc = ::poll(&p, 1, static_cast<int>(std::min<std::int64_t>(left_ms, 1000)));
        if (rc > 0) return true;
        if (rc < 0 && errno != EINTR) return false;
    }
}

ssize_t send_some(int fd, const std::uint8_t* data, std::size_t size) noexcept {
    for (;;) {
        const ssize_t n = ::send(fd, data, size, MSG_NOSIGNAL);
        if (n >= 0) return n;
        if (errno == EINTR) continue;
        return errno == EWOULDBLOCK ? -EAGAIN : -errno;
    }
}

}  // namespace

TlsLinkShared::~TlsLinkShared() {
    if (saved_ != nullptr) net::free_tls_session(saved_);
}

SSL_SESSION* TlsLinkShared::take_saved() {
    std::lock_guard lock(mutex_);
    if (!resume || saved_ == nullptr) return nullptr;
    // One reference for the caller, one kept for the next connection.
    return SSL_SESSION_up_ref(saved_) == 1 ? saved_ : nullptr;
}

void TlsLinkShared::keep(SSL_SESSION* session) {
    std::lock_guard lock(mutex_);
    if (saved_ != nullptr) net::free_tls_session(saved_);
    saved_ = session;
}

void TlsLinkShared::failed(std::string why) {
    ++handshake_failures;
    std::lock_guard lock(mutex_);
    last_failure_ = std::move(why);
}

std::string TlsLinkShared::last_failure() const {
    std::lock_guard lock(mutex_);
    return last_failure_;
}

TlsLink::TlsLink(net::UniqueFd fd, std::unique_ptr<net::TlsSession> session,
                 std::shared_ptr<TlsLinkShared> shared)
    : fd_(std::move(fd)), session_(std::move(session)), shared_(std::move(shared)) {
    out_.reserve(4096);
    plain_.reserve(4096);
    // Records that came with the end of the handshake (TLS 1.3 tickets): processed now, so
    // that nothing decrypted hides from poll().
    decrypt();
}

TlsLink::~TlsLink() {
    // The session a later connection resumes: taken at the end, when a TLS 1.3 ticket that
    // came after the handshake has been read.
    if (shared_->resume && session_->established())
        if (SSL_SESSION* s = session_->saved_session()) shared_->keep(s);
}

ssize_t TlsLink::flush() noexcept {
    while (out_pos_ < out_.size()) {
        const ssize_t n = send_some(fd_.get(), out_.data() + out_pos_, out_.size() - out_pos_);
        if (n == -EAGAIN) return 0;
        if (n < 0) return n;
        out_pos_ += static_cast<std::size_t>(n);
    }
    out_.clear();
    out_pos_ = 0;
    return 0;
}

ssize_t TlsLink::send(const std::uint8_t* data, std::size_t size) noexcept {
    if (const ssize_t e = flush(); e < 0) return e;
    if (out_pos_ < out_.size()) return -EAGAIN;
    if (size == 0) return 0;
    if (session_->write(data, size) != net::TlsStatus::Ok) return -EPROTO;
    try {
        session_->take_output(out_);
    } catch (...) {
        return -ENOMEM;
    }
    const std::int64_t deadline = net::now_ns() + kSendDrainMs * net::kNsPerMs;
    for (;;) {
        if (const ssize_t e = flush(); e < 0) return e;
        if (out_pos_ == out_.size() || !wait_for(fd_.get(), POLLOUT, deadline)) break;
    }
    return static_cast<ssize_t>(size);
}

void TlsLink::decrypt() noexcept {
    std::uint8_t chunk[16384];
    for (;;) {
        std::size_t n = 0;
        const net::TlsStatus st = session_->read(chunk, sizeof chunk, n);
        if (n > 0) {
            try {
                plain_.insert(plain_.end(), chunk, chunk + n);
            } catch (...) {
                ended_ = true;
                end_code_ = -ENOMEM;
                return;
            }
            continue;
        }
        if (st == net::TlsStatus::Closed && !ended_) {
            ended_ = true;
            end_code_ = 0;
        } else if (st == net::TlsStatus::Failed && !ended_) {
            ended_ = true;
            end_code_ = -EPROTO;
            shared_->failed("TLS session refused or broken: " + session_->error());
        }
        return;
    }
}

void TlsLink::pull() noexcept {
    if (ended_) return;
    std::uint8_t buf[16384];
    for (;;) {
        const ssize_t n = ::recv(fd_.get(), buf, sizeof buf, 0);
        if (n > 0) {
            session_->feed(buf, static_cast<std::size_t>(n));
            continue;
        }
        const int err = n < 0 ? errno : 0;  // before OpenSSL touches errno
        if (err == EINTR) continue;
        decrypt();
        if (ended_) return;
        if (n == 0) {
            ended_ = true;
            end_code_ = 0;
        } else if (err != EAGAIN && err != EWOULDBLOCK) {
            ended_ = true;
            end_code_ = -err;
        }
        // Replies the session owes (key updates) go out with the next send or recv.
        if (session_->pending_output() > 0) {
            try {
                session_->take_output(out_);
            } catch (...) {
            }
        }
        return;
    }
}

ssize_t TlsLink::recv(std::uint8_t* data, std::size_t size) noexcept {
    if (!ended_) {
        if (const ssize_t e = flush(); e < 0) {
            ended_ = true;
            end_code_ = e;
        }
    }
    if (plain_pos_ == plain_.size()) {
        plain_.clear();
        plain_pos_ = 0;
        pull();
    }
    if (plain_pos_ < plain_.size()) {
        const std::size_t n = std::min(size, plain_.size() - plain_pos_);
        std::memcpy(data, plain_.data() + plain_pos_, n);
        plain_pos_ += n;
        return static_cast<ssize_t>(n);
    }
    return ended_ ? end_code_ : -EAGAIN;
}

std::int64_t TlsLink::unread_by_target() const noexcept {
    const std::int64_t unread = net::bytes_unread_by_peer(fd_.get());
    return unread < 0 ? -1 : unread + static_cast<std::int64_t>(out_.size() - out_pos_);
}

void TlsLink::shutdown_write() noexcept {
    session_->close();
    try {
        session_->take_output(out_);
    } catch (...) {
    }
    const std::int64_t deadline = net::now_ns() + kSendDrainMs * net::kNsPerMs;
    while (flush() == 0 && out_pos_ < out_.size() && wait_for(fd_.get(), POLLOUT, deadline)) {
    }
    ::shutdown(fd_.get(), SHUT_WR);
}

ssize_t TlsLink::send_beside_session(const std::uint8_t* data, std::size_t size,
                                     int timeout_ms) noexcept {
    const std::int64_t deadline = net::now_ns() + std::int64_t{timeout_ms} * net::kNsPerMs;
    // The session's own records go first, whole.
    while (out_pos_ < out_.size()) {
        if (const ssize_t e = flush(); e < 0) return e;
        if (out_pos_ < out_.size() && !wait_for(fd_.get(), POLLOUT, deadline)) return -EAGAIN;
    }
    std::size_t done = 0;
    while (done < size) {
        const ssize_t n = send_some(fd_.get(), data + done, size - done);
        if (n > 0) {
            done += static_cast<std::size_t>(n);
        } else if (n == -EAGAIN) {
            if (!wait_for(fd_.get(), POLLOUT, deadline)) break;
        } else {
            return done > 0 ? static_cast<ssize_t>(done) : n;
        }
    }
    return static_cast<ssize_t>(done);
}

std::unique_ptr<Link> TlsConnector::open_plain(int timeout_ms, int& error) {
    return TcpConnector(target_).open(timeout_ms, error);
}

std::unique_ptr<Link> TlsConnector::open(int timeout_ms, int& error) {
    const std::int64_t deadline = net::now_ns() + std::int64_t{timeout_ms} * net::kNsPerMs;
    const int raw = connect_with_timeout(target_, timeout_ms);
    if (raw < 0) {
        error = -raw;
        return nullptr;
    }
    net::UniqueFd fd(raw);
    SSL_SESSION* offer = shared_->take_saved();
    auto session = std::make_unique<net::TlsSession>(shared_->ctx, offer);
    if (offer != nullptr) net::free_tls_session(offer);  // the SSL holds its own reference
    auto fail = [&](int code, std::string why) -> std::unique_ptr<Link> {
        shared_->failed(std::move(why));
        error = code;
        return nullptr;
    };
    if (!session->valid()) return fail(ENOMEM, session->error());
    std::vector<std::uint8_t> out;
    std::uint8_t buf[16384];
    for (;;) {
        const net::TlsStatus st = session->handshake();
        out.clear();
        session->take_output(out);
        for (std::size_t sent = 0; sent < out.size();) {
            const ssize_t n = send_some(fd.get(), out.data() + sent, out.size() - sent);
            if (n > 0) {
                sent += static_cast<std::size_t>(n);
            } else if (n != -EAGAIN) {
                return fail(static_cast<int>(-n), "connection broke during the TLS handshake");
            } else if (!wait_for(fd.get(), POLLOUT, deadline)) {
                return fail(ETIMEDOUT, "no TLS handshake within the timeout");
            }
        }
        if (st == net::TlsStatus::Ok) break;
        if (st != net::TlsStatus::WantMore)
            return fail(EPROTO, "TLS handshake refused: " + session->error());
        if (!wait_for(fd.get(), POLLIN, deadline))
            return fail(ETIMEDOUT, "no TLS handshake within the timeout");
        const ssize_t n = ::recv(fd.get(), buf, sizeof buf, 0);
        const int err = n < 0 ? errno : 0;
        if (n == 0)
            return fail(ECONNRESET, "the target closed the connection during the handshake");
        if (n < 0) {
            if (err == EAGAIN || err == EWOULDBLOCK || err == EINTR) continue;
            return fail(err, std::string("TLS handshake: ") + std::strerror(err));
        }
        session->feed(buf, static_cast<std::size_t>(n));
    }
    ++shared_->handshakes;
    if (session->resumed()) ++shared_->resumed;
    error = 0;
    return std::make_unique<TlsLink>(std::move(fd), std::move(session), shared_);
}

}  // namespace mbstorm::netfuzz
