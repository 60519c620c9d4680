// Modbus/TCP Security on the server: the role allow-list that says which function codes each
// client role may use (a connection's TLS session is its link's: server/link.hpp).
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
#include "util/error.hpp"

namespace mbstorm::server {

using FunctionSet = codec::FunctionSet;

// Which function codes each role (from the client certificate's role extension) may use.
// Empty: every role may use every function. Otherwise a role not listed may use none, and a
// request outside its role's set is answered with exception 01 (Illegal Function).
class TlsRoles {
  public:
    // Adds "ROLE=FC,FC-FC,..." (decimal or 0x hex codes). InvalidInput when malformed.
    Error add_rule(std::string_view text);
    // Adds one role's set (device descriptions).
    void allow(std::string role, const FunctionSet& functions);
    bool empty() const noexcept { return roles_.empty(); }
    // The set for `role`; nullptr when nothing is restricted.
    const FunctionSet* allowed_for(std::string_view role) const noexcept;

  private:
    std::vector<std::pair<std::string, FunctionSet>> roles_;
};

}  // namespace mbstorm::server
