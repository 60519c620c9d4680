// How many of the bytes sent on a TCP socket the peer's program has not read yet, when the
// peer's socket lives on this host (loopback, or an address of ours): the kernel's socket
// diagnostics show its receive queue. The fuzzer uses it to deliver a split frame as two
// reads on the target however loaded the machine: it sends the second piece only once the
// target has read the first.
#pragma once

#include <cstdint>

namespace mbstorm::net {

// Bytes sent on `fd` not yet read by the peer's program (our unacknowledged bytes included),
// or -1 when that cannot be known: the peer's socket is on another host or in another network
// namespace, the socket is not connected TCP, or socket diagnostics are not available.
std::int64_t bytes_unread_by_peer(int fd) noexcept;

}  // namespace mbstorm::net
