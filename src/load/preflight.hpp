// Checks before a run opens any socket: name resolution, the open-files limit (raised where
// allowed) and the ephemeral port range, each with a message saying what caps the run.
#pragma once

#include <cstdint>
#include <string>

#include "net/socket.hpp"
#include "util/error.hpp"

namespace mbstorm::load {

struct PortRange {
    std::uint32_t low = 32768;
    std::uint32_t high = 60999;
    std::uint32_t size() const noexcept { return high >= low ? high - low + 1 : 0; }
};

// Reads /proc/sys/net/ipv4/ip_local_port_range; false when it cannot be read.
bool read_port_range(PortRange& out, const char* path = "/proc/sys/net/ipv4/ip_local_port_range");

// "host:port" with brackets for IPv6 literals.
std::string endpoint_text(const std::string& host, std::uint16_t port);

// The numeric address of an endpoint, without port ("127.0.0.1", "::1").
std::string numeric_address(const net::Endpoint& endpoint);

// None when `connections` fit both limits (raising RLIMIT_NOFILE if needed), else Refused.
// Each source address has the whole ephemeral port range (0 sources: the kernel's one).
// With `direct` descriptors sockets take no descriptor, but each thread's ring holds its share
// of the connections in a table the kernel caps at the open-files limit.
Error check_connection_capacity(std::uint32_t connections, std::uint32_t threads,
                                std::size_t source_addresses = 0, bool direct = false);

// Direct descriptors: the threads needed (at least `threads`) so that each ring's share of
// `connections` fits the open-files limit, raised first as far as allowed.
std::uint32_t threads_for_socket_tables(std::uint32_t connections, std::uint32_t threads);

}  // namespace mbstorm::load
