#include "net/source_addresses.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <cerrno>
#include <cstring>

namespace mbstorm::net {
namespace {

constexpr std::string_view kForms =
    "give numeric addresses and ranges separated by commas, e.g. 127.0.0.1-127.0.0.20,::1";

std::string_view trim(std::string_view s) {
    while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
    return s;
}

// A numeric address, with or without IPv6 brackets.
bool parse_address(std::string_view text, Endpoint& out) {
    if (text.size() >= 2 && text.front() == '[' && text.back() == ']')
        text = text.substr(1, text.size() - 2);
    const std::string host(text);
    out = Endpoint{};
    auto* in = reinterpret_cast<sockaddr_in*>(&out.addr);
    if (inet_pton(AF_INET, host.c_str(), &in->sin_addr) == 1) {
        in->sin_family = AF_INET;
        out.len = sizeof(sockaddr_in);
        return true;
    }
    auto* in6 = reinterpret_cast<sockaddr_in6*>(&out.addr);
    if (inet_pton(AF_INET6, host.c_str(), &in6->sin6_addr) == 1) {
        in6->sin6_family = AF_INET6;
        out.len = sizeof(sockaddr_in6);
        return true;
    }
    return false;
}

// The address bytes in network order (4 or 16 of them).
std::uint8_t* address_bytes(Endpoint& ep, std::size_t& size) {
    if (ep.family() == AF_INET) {
        size = 4;
        return reinterpret_cast<std::uint8_t*>(&reinterpret_cast<sockaddr_in*>(&ep.addr)->sin_addr);
    }
    size = 16;
    return reinterpret_cast<std::uint8_t*>(&reinterpret_cast<sockaddr_in6*>(&ep.addr)->sin6_addr);
}

// Appends first..last; false with `error` when the range is backwards or too wide.
bool expand_range(Endpoint first, Endpoint last, std::string_view entry, std::vector<Endpoint>& out,
                  std::string& error) {
    std::size_t size = 0;
    std::uint8_t* a = address_bytes(first, size);
    const std::uint8_t* b = address_bytes(last, size);
    // Ranges step the last 16 bits; everything before must be the same.
    if (std::memcmp(a, b, size - 2) != 0) {
        error = "source address range '" + std::string(entry) +
                "' spans more than 65536 addresses (only the last 16 bits may differ)";
        return false;
    }
    const unsigned low = (unsigned{a[size - 2]} << 8) | a[size - 1];
    const unsigned high = (unsigned{b[size - 2]} << 8) | b[size - 1];
    if (high < low) {
        error = "source address range '" + std::string(entry) + "' ends before it starts";
        return false;
    }
    if (out.size() + (high - low + 1) > kMaxSourceAddresses) {
        error = "more than " + std::to_string(kMaxSourceAddresses) + " source addresses";
        return false;
    }
    for (unsigned v = low; v <= high; ++v) {
        a[size - 2] = static_cast<std::uint8_t>(v >> 8);
        a[size - 1] = static_cast<std::uint8_t>(v);
        out.push_back(first);
    }
    return true;
}

}  // namespace

bool parse_source_addresses(std::string_view text, std::vector<Endpoint>& out, std::string& error) {
    out.clear();
    if (trim(text).empty()) return true;
    while (true) {
        const auto comma = text.find(',');
        const std::string_view entry = trim(text.substr(0, comma));
        if (entry.empty()) {
            error = "empty entry in the source address list '" + std::string(text) + "'; " +
                    std::string(kForms);
            return false;
        }
        const auto dash = entry.find('-');
        Endpoint first, last;
        if (dash == std::string_view::npos) {
            if (!parse_address(entry, first)) {
                error = "'" + std::string(entry) + "' is not a numeric IPv4 or IPv6 address; " +
                        std::string(kForms);
                return false;
            }
            if (out.size() >= kMaxSourceAddresses) {
                error = "more than " + std::to_string(kMaxSourceAddresses) + " source addresses";
                return false;
            }
            out.push_back(first);
        } else {
            const std::string_view from = trim(entry.substr(0, dash));
            const std::string_view to = trim(entry.substr(dash + 1));
            if (!parse_address(from, first) || !parse_address(to, last)) {
                error = "'" + std::string(entry) + "' is not a range FIRST-LAST of numeric " +
                        "addresses; " + std::string(kForms);
                return false;
            }
            if (first.family() != last.family()) {
                error = "source address range '" + std::string(entry) + "' mixes IPv4 and IPv6";
                return false;
            }
            if (!expand_range(first, last, entry, out, error)) return false;
        }
        if (comma == std::string_view::npos) return true;
        text = text.substr(comma + 1);
    }
}

std::string check_source_is_local(const Endpoint& source) {
    UniqueFd fd(::socket(source.family(), SOCK_STREAM | SOCK_CLOEXEC, 0));
    std::string address = source.to_string();
    address = address.substr(0, address.rfind(':'));  // no port
    if (!fd.valid()) return "cannot test source address " + address + ": " + std::strerror(errno);
    const int one = 1;
    ::setsockopt(fd.get(), SOL_IP, IP_BIND_ADDRESS_NO_PORT, &one, sizeof one);
    if (::bind(fd.get(), source.sa(), source.len) == 0) return {};
    const int e = errno;
    if (e == EADDRNOTAVAIL)
        return "source address " + address + " is not an address of this machine";
    return "cannot bind to source address " + address + ": " + std::strerror(e);
}

}  // namespace mbstorm::net
