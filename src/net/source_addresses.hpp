// Local addresses a client binds its connections to before connecting (`run --source-addr`):
// past one address's ephemeral ports, more connections to one target need more source
// addresses. Text form: a comma list of numeric IPv4/IPv6 addresses and ranges "FIRST-LAST"
// (both ends included, same family, differing in their last 16 bits at most).
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "net/socket.hpp"
#include "util/error.hpp"

namespace mbstorm::net {

// At most this many addresses in one list (ranges expanded).
inline constexpr std::size_t kMaxSourceAddresses = 65536;

// Parses the list into endpoints (port 0), in the order given. Empty text gives an empty list.
// InvalidInput naming the offending entry and the accepted forms.
Result<std::vector<Endpoint>> parse_source_addresses(std::string_view text);

// Success when a socket can bind to `source` on this machine; else why not: NotFound when it
// is not an address of this machine, Network when the bind fails otherwise.
Error check_source_is_local(const Endpoint& source);

}  // namespace mbstorm::net
