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

// A list entry that cannot be used as a source address.
Error bad_list(std::string why) {
    return Error(ErrorCode::InvalidInput, std::move(why));
}

// Appends first..last; an error when the range is backwards or too wide.
Error expand_range(Endpoint first, Endpoint last, std::string_view entry,
                   std::vector<Endpoint>& out) {
    std::size_t size = 0;
    std::uint8_t* a = address_bytes(first, size);
    const std::uint8_t* b = address_bytes(last, size);
    // Ranges step the last 16 bits; everything before must be the same.
    if (std::memcmp(a, b, size - 2) != 0) {
        return bad_list("source address range '" + std::string(entry) +
                        "' spans more than 65536 addresses (only the last 16 bits may differ)");
    }
    const unsigned low = (unsigned{a[size - 2]} << 8) | a[size - 1];
    const unsigned high = (unsigned{b[size - 2]} << 8) | b[size - 1];
    if (high < low) {
        return bad_list("source address range '" + std::string(entry) + "' ends before it starts");
    }
    if (out.size() + (high - low + 1) > kMaxSourceAddresses) {
        return bad_list("more than " + std::to_string(kMaxSourceAddresses) + " source addresses");
    }
    for (unsigned v = low; v <= high; ++v) {
        a[size - 2] = static_cast<std::uint8_t>(v >> 8);
        a[size - 1] = static_cast<std::uint8_t>(v);
        out.push_back(first);
    }
    return Error::none();
}

}  // namespace

Result<std::vector<Endpoint>> parse_source_addresses(std::string_view text) {
    std::vector<Endpoint> out;
    if (trim(text).empty()) return out;
    while (true) {
        const auto comma = text.find(',');
        const std::string_view entry = trim(text.substr(0, comma));
        if (entry.empty()) {
            return bad_list("empty entry in the source address list '" + std::string(text) + "'; " +
                            std::string(kForms));
        }
        const auto dash = entry.find('-');
        Endpoint first, last;
        if (dash == std::string_view::npos) {
            if (!parse_address(entry, first)) {
                return bad_list("'" + std::string(entry) +
                                "' is not a numeric IPv4 or IPv6 address; " + std::string(kForms));
            }
            if (out.size() >= kMaxSourceAddresses) {
                return bad_list("more than " + std::to_string(kMaxSourceAddresses) +
                                " source addresses");
            }
            out.push_back(first);
        } else {
            const std::string_view from = trim(entry.substr(0, dash));
            const std::string_view to = trim(entry.substr(dash + 1));
            if (!parse_address(from, first) || !parse_address(to, last)) {
                return bad_list("'" + std::string(entry) +
                                "' is not a range FIRST-LAST of numeric " + "addresses; " +
                                std::string(kForms));
            }
            if (first.family() != last.family()) {
                return bad_list("source address range '" + std::string(entry) +
                                "' mixes IPv4 and IPv6");
            }
            if (Error bad = expand_range(first, last, entry, out); !bad.ok()) return bad;
        }
        if (comma == std::string_view::npos) return out;
        text = text.substr(comma + 1);
    }
}

Error check_source_is_local(const Endpoint& source) {
    UniqueFd fd(::socket(source.family(), SOCK_STREAM | SOCK_CLOEXEC, 0));
    std::string address = source.to_string();
    address = address.substr(0, address.rfind(':'));  // no port
    if (!fd.valid())
        return from_errno(ErrorCode::Network, errno, "cannot test source address " + address);
    const int one = 1;
    ::setsockopt(fd.get(), SOL_IP, IP_BIND_ADDRESS_NO_PORT, &one, sizeof one);
    if (::bind(fd.get(), source.sa(), source.len) == 0) return Error::none();
    const int e = errno;
    if (e == EADDRNOTAVAIL)
        return Error(ErrorCode::NotFound,
                     "source address " + address + " is not an address of this machine");
    return from_errno(ErrorCode::Network, e, "cannot bind to source address " + address);
}

}  // namespace mbstorm::net
