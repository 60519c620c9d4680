// A load connection's Modbus/TCP Security state: its TLS session over memory BIOs, the
// ciphertext being sent, and the session kept for resumption when the connection reopens.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "net/tls_session.hpp"

namespace mbstorm::load {

struct TlsLink {
    TlsLink() { cipher.reserve(4096); }
    ~TlsLink() {
        if (saved != nullptr) net::free_tls_session(saved);
    }
    TlsLink(const TlsLink&) = delete;
    TlsLink& operator=(const TlsLink&) = delete;

    std::optional<net::TlsSession> session;  // one per TCP connection
    std::vector<std::uint8_t> cipher;        // ciphertext of the send in flight
    SSL_SESSION* saved = nullptr;            // --tls-resume: offered on the next connect
    std::int64_t handshake_started_ns = 0;
    // The kernel's TLS carries this connection's records (ktls_offload.hpp): plaintext both
    // ways through the plain paths from here on; the session stays only to be resumed.
    bool kernel = false;
    bool stays_in_userspace = false;  // the hand-off was refused for good
};

}  // namespace mbstorm::load
