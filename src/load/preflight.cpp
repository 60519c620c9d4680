#include "load/preflight.hpp"

#include <arpa/inet.h>
#include <fmt/format.h>

#include "load/plan.hpp"

#include <algorithm>
#include <cstdio>

namespace mbstorm::load {

bool read_port_range(PortRange& out, const char* path) {
    std::FILE* f = std::fopen(path, "r");
    if (f == nullptr) return false;
    unsigned low = 0, high = 0;
    const bool ok = std::fscanf(f, "%u %u", &low, &high) == 2;
    std::fclose(f);
    if (ok) out = PortRange{low, high};
    return ok;
}

std::string endpoint_text(const std::string& host, std::uint16_t port) {
    const bool v6_literal = host.find(':') != std::string::npos && host.front() != '[';
    return v6_literal ? fmt::format("[{}]:{}", host, port) : fmt::format("{}:{}", host, port);
}

std::string numeric_address(const net::Endpoint& endpoint) {
    char text[INET6_ADDRSTRLEN] = {};
    if (endpoint.family() == AF_INET) {
        const auto* sin = reinterpret_cast<const sockaddr_in*>(&endpoint.addr);
        inet_ntop(AF_INET, &sin->sin_addr, text, sizeof(text));
    } else if (endpoint.family() == AF_INET6) {
        const auto* sin6 = reinterpret_cast<const sockaddr_in6*>(&endpoint.addr);
        inet_ntop(AF_INET6, &sin6->sin6_addr, text, sizeof(text));
    }
    return text;
}

namespace {

// "" when the connections fit, else why not.
std::string capacity_problem(std::uint32_t connections, std::uint32_t threads,
                             std::size_t source_addresses, bool direct) {
    // Ports first: no descriptor limit helps when the ports run out.
    PortRange range;
    const std::uint64_t addresses = std::max<std::uint64_t>(source_addresses, 1);
    if (read_port_range(range) && connections > range.size() * addresses) {
        if (source_addresses > 0) {
            return fmt::format(
                "connections: {} exceed what {} source address{} can hold towards one target "
                "({} ephemeral ports each, {}-{} in /proc/sys/net/ipv4/ip_local_port_range); give "
                "at least {} source addresses with --source-addr",
                connections, source_addresses, source_addresses == 1 ? "" : "es", range.size(),
                range.low, range.high, (connections + range.size() - 1) / range.size());
        }
        return fmt::format(
            "connections: {} exceed the ephemeral port range {}-{} ({} ports towards one target "
            "address, /proc/sys/net/ipv4/ip_local_port_range); widen it with `sysctl -w "
            "net.ipv4.ip_local_port_range=\"1024 65535\"`, spread the connections over several "
            "source addresses (--source-addr) or use at most {} connections",
            connections, range.low, range.high, range.size(), range.size());
    }
    if (direct) {
        const std::uint64_t per_ring = (std::uint64_t{connections} + threads - 1) / threads;
        std::string why;
        const std::uint64_t limit = net::raise_nofile_limit(per_ring + 64, &why);
        if (limit >= per_ring) return {};
        return fmt::format(
            "connections: {} over {} thread{} need {} io_uring socket slots per thread, above the "
            "open-files limit {} that caps a ring's table ({}); use --threads {} or more",
            connections, threads, threads == 1 ? "" : "s", per_ring, limit, why,
            (connections + limit - 1) / std::max<std::uint64_t>(limit, 1));
    }
    // Each thread also holds a ring (and a few fds), the process its stdio and friends.
    const std::uint64_t wanted = std::uint64_t{connections} + 8ull * threads + 64;
    std::string why;
    const std::uint64_t limit = net::raise_nofile_limit(wanted, &why);
    if (limit < wanted) {
        return fmt::format(
            "connections: {} cannot be opened: the open-files limit allows about {} ({})",
            connections, limit > 8ull * threads + 64 ? limit - 8ull * threads - 64 : 0, why);
    }
    return {};
}

}  // namespace

Error check_connection_capacity(std::uint32_t connections, std::uint32_t threads,
                                std::size_t source_addresses, bool direct) {
    std::string why = capacity_problem(connections, threads, source_addresses, direct);
    if (why.empty()) return {};
    return Error(ErrorCode::Refused, std::move(why));
}

std::uint32_t threads_for_socket_tables(std::uint32_t connections, std::uint32_t threads) {
    const std::uint64_t limit = net::raise_nofile_limit(std::uint64_t{connections} + 64);
    if (limit == 0) return threads;
    const std::uint64_t needed = (connections + limit - 1) / limit;
    return static_cast<std::uint32_t>(
        std::min<std::uint64_t>(std::max<std::uint64_t>(threads, needed), kMaxThreads));
}

}  // namespace mbstorm::load
