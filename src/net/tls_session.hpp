// One TLS connection over memory BIOs: the caller moves the ciphertext (io_uring recv and
// send), the session turns it into plaintext and back. No socket is ever touched here.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "net/ktls_offload.hpp"
#include "net/tls_context.hpp"

using SSL_SESSION = struct ssl_session_st;
using BIO = struct bio_st;

namespace mbstorm::net {

enum class TlsStatus : unsigned char {
    Ok,        // progress made (or nothing to do)
    WantMore,  // needs more ciphertext from the peer
    Closed,    // the peer sent close_notify
    Failed,    // handshake refused or a record did not verify: close the connection
};

class TlsSession {
  public:
    // `resume`: a session saved from an earlier connection to offer for resumption (client).
    TlsSession(std::shared_ptr<TlsContext> ctx, SSL_SESSION* resume = nullptr);
    ~TlsSession();
    TlsSession(const TlsSession&) = delete;
    TlsSession& operator=(const TlsSession&) = delete;

    bool valid() const noexcept { return ssl_ != nullptr; }

    // Ciphertext that arrived from the peer.
    void feed(const std::uint8_t* data, std::size_t size) noexcept;
    // Drives the handshake: Ok once it is complete, WantMore while it waits on the peer.
    TlsStatus handshake() noexcept;
    bool established() const noexcept { return established_; }
    // Decrypted bytes into `out`: `size` gets how many (0 with WantMore: none yet).
    TlsStatus read(std::uint8_t* out, std::size_t capacity, std::size_t& size) noexcept;
    // Encrypts `size` plaintext bytes (all of them: the memory BIO grows).
    TlsStatus write(const std::uint8_t* data, std::size_t size) noexcept;
    // Ciphertext waiting to go to the peer, appended to `out` (keeps its capacity).
    std::size_t take_output(std::vector<std::uint8_t>& out);
    std::size_t pending_output() const noexcept;
    // Ciphertext from the peer not yet made into plaintext: a record that has not all come.
    bool partial_input() const noexcept;
    // Queues close_notify (take_output sends it).
    void close() noexcept;

    // After the handshake: the peer's role (server side), whether this session was resumed,
    // the protocol version's name, and why it failed.
    std::string peer_role() const;
    bool resumed() const noexcept;
    const char* version() const noexcept;
    const std::string& error() const noexcept { return error_; }
    // A session to resume later (the caller owns the reference), nullptr when none.
    SSL_SESSION* saved_session() const noexcept;

    // Kernel TLS hand-off: counts records and keeps the traffic secrets from here on (call
    // before the handshake, on a session whose context had KtlsTracker::prepare_context).
    void track_for_offload();
    // What the hand-off decision rests on now (kernel_available and real_fd left false).
    KtlsReadiness offload_readiness() const noexcept;
    // The hand-off parameters now; false when not tracked or not derivable.
    bool offload_params(KtlsParams& out) const noexcept;

  private:
    TlsStatus fail(int rc) noexcept;

    std::shared_ptr<TlsContext> ctx_;
    SSL* ssl_ = nullptr;
    BIO* in_ = nullptr;   // ciphertext from the peer (owned by ssl_)
    BIO* out_ = nullptr;  // ciphertext to the peer (owned by ssl_)
    bool established_ = false;
    std::string error_;
    std::unique_ptr<KtlsTracker> ktls_;  // only when the kernel could take the records
};

void free_tls_session(SSL_SESSION* session) noexcept;

}  // namespace mbstorm::net
