// The fuzzer's byte stream over Modbus/TCP Security: MBAP inside a TLS session (OpenSSL over
// memory BIOs, net/tls_session) on a TCP connection. The handshake completes inside open(),
// within the open timeout; after it, send and recv are as non-blocking as a TcpLink's. The
// Modbus inside is what gets fuzzed: the records themselves are always well-formed, except
// where a case deliberately writes bytes beside the session (send_beside_session).
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "net/socket.hpp"
#include "net/tls_context.hpp"
#include "net/tls_session.hpp"
#include "netfuzz/link.hpp"

namespace mbstorm::netfuzz {

// What the links of one TlsConnector share: the session to resume (--tls-resume), counters,
// and why the last handshake or session failed.
struct TlsLinkShared {
    TlsLinkShared(std::shared_ptr<net::TlsContext> c, bool r) : ctx(std::move(c)), resume(r) {}
    ~TlsLinkShared();
    TlsLinkShared(const TlsLinkShared&) = delete;
    TlsLinkShared& operator=(const TlsLinkShared&) = delete;

    // A new reference to the session to offer, or nullptr (the caller frees it).
    SSL_SESSION* take_saved();
    void keep(SSL_SESSION* session);  // takes the reference
    void failed(std::string why);
    std::string last_failure() const;

    const std::shared_ptr<net::TlsContext> ctx;
    const bool resume;
    std::atomic<std::uint64_t> handshakes{0}, resumed{0}, handshake_failures{0};

  private:
    mutable std::mutex mutex_;
    SSL_SESSION* saved_ = nullptr;
    std::string last_failure_;
};

class TlsLink final : public Link {
  public:
    TlsLink(net::UniqueFd fd, std::unique_ptr<net::TlsSession> session,
            std::shared_ptr<TlsLinkShared> shared);
    ~TlsLink() override;

    int poll_fd() const noexcept override { return fd_.get(); }
    // Decrypted bytes not yet returned, or an end of stream not yet reported.
    bool has_buffered_input() const noexcept override {
        return plain_pos_ < plain_.size() || ended_;
    }
    // Encrypts all of `data` (one or more records) and sends what the socket takes; the rest
    // follows on the next call, or now if the socket drains within a moment. -EAGAIN while
    // ciphertext from an earlier call still waits for the socket.
    ssize_t send(const std::uint8_t* data, std::size_t size) noexcept override;
    // Decrypted bytes; 0 when the peer sent close_notify or closed the TCP stream; -EPROTO
    // when a record did not verify or the peer sent a fatal alert.
    ssize_t recv(std::uint8_t* data, std::size_t size) noexcept override;
    // close_notify, then the TCP half-close.
    void shutdown_write() noexcept override;
    // Ciphertext not yet taken by the socket counts as unread too.
    std::int64_t unread_by_target() const noexcept override;

    // Bytes written to the socket as they are, between the session's records (a case that
    // puts plaintext into an established session). Blocks up to `timeout_ms` for the socket.
    ssize_t send_beside_session(const std::uint8_t* data, std::size_t size,
                                int timeout_ms) noexcept;
    bool resumed() const noexcept { return session_->resumed(); }
    const char* version() const noexcept { return session_->version(); }

  private:
    // Sends queued ciphertext until the socket would block: 0, or -errno when it broke.
    ssize_t flush() noexcept;
    // Reads what the socket has and decrypts all of it into plain_.
    void pull() noexcept;
    void decrypt() noexcept;

    net::UniqueFd fd_;
    std::unique_ptr<net::TlsSession> session_;
    std::shared_ptr<TlsLinkShared> shared_;
    std::vector<std::uint8_t> out_;  // ciphertext not yet taken by the socket, from out_pos_
    std::size_t out_pos_ = 0;
    std::vector<std::uint8_t> plain_;  // decrypted, not yet returned, from plain_pos_
    std::size_t plain_pos_ = 0;
    bool ended_ = false;  // the stream is over: end_code_ is what recv() reports
    ssize_t end_code_ = 0;
};

class TlsConnector final : public Connector {
  public:
    TlsConnector(const net::Endpoint& target, std::shared_ptr<net::TlsContext> ctx, bool resume)
        : target_(target), shared_(std::make_shared<TlsLinkShared>(std::move(ctx), resume)) {}
    // TCP connect, then the TLS handshake, both within `timeout_ms`. Errors: connect's errno,
    // ETIMEDOUT (no handshake in time), ECONNRESET (closed during it), EPROTO (refused; see
    // last_failure()).
    std::unique_ptr<Link> open(int timeout_ms, int& error) override;
    std::string describe() const override { return target_.to_string() + " (TLS)"; }
    // The TCP connection alone, no handshake: for cases that send the TLS port something
    // other than TLS.
    std::unique_ptr<Link> open_plain(int timeout_ms, int& error);

    const net::Endpoint& target() const noexcept { return target_; }
    const TlsLinkShared& shared() const noexcept { return *shared_; }
    std::string last_failure() const { return shared_->last_failure(); }

  private:
    net::Endpoint target_;
    std::shared_ptr<TlsLinkShared> shared_;
};

}  // namespace mbstorm::netfuzz
