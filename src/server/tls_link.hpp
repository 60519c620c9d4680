// Modbus/TCP Security on the server: a connection's TLS session with the ciphertext it is
// sending, and the role allow-list that says which function codes each client role may use.
#pragma once

#include <bitset>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "codec/function_set.hpp"
#include "net/tls_session.hpp"

namespace mbstorm::server {

using FunctionSet = codec::FunctionSet;

// Which function codes each role (from the client certificate's role extension) may use.
// Empty: every role may use every function. Otherwise a role not listed may use none, and a
// request outside its role's set is answered with exception 01 (Illegal Function).
class TlsRoles {
  public:
    // Adds "ROLE=FC,FC-FC,..." (decimal or 0x hex codes). False with `error` when malformed.
    bool add_rule(std::string_view text, std::string& error);
    // Adds one role's set (device descriptions).
    void allow(std::string role, const FunctionSet& functions);
    bool empty() const noexcept { return roles_.empty(); }
    // The set for `role`; nullptr when nothing is restricted.
    const FunctionSet* allowed_for(std::string_view role) const noexcept;

  private:
    std::vector<std::pair<std::string, FunctionSet>> roles_;
};

struct TlsLink {
    explicit TlsLink(std::shared_ptr<net::TlsContext> ctx) : session(std::move(ctx)) {
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
    const FunctionSet* allowed = nullptr;  // nullptr: every function
    // Admitted one over the connection limit when every connection held had authenticated:
    // the oldest idle one is evicted only once this handshake succeeds.
    bool evict_when_established = false;
    // The kernel's TLS carries the records (ktls_offload.hpp): plaintext both ways from here
    // on, through the plain paths; the session stays for the role and is never used again.
    bool kernel = false;
    bool stays_in_userspace = false;  // the hand-off was refused for good
};

}  // namespace mbstorm::server
