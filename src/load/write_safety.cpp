#include "load/write_safety.hpp"

#include <arpa/inet.h>
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cstring>

#include "codec/function_code.hpp"

namespace mbstorm::load {

bool is_loopback_address(std::string_view address) noexcept {
    char text[INET6_ADDRSTRLEN + 1] = {};
    // Accept "[::1]" as written in URLs.
    if (address.size() >= 2 && address.front() == '[' && address.back() == ']') {
        address = address.substr(1, address.size() - 2);
    }
    if (address.empty() || address.size() >= sizeof(text)) return false;
    std::memcpy(text, address.data(), address.size());

    in_addr v4{};
    if (inet_pton(AF_INET, text, &v4) == 1) {
        return (ntohl(v4.s_addr) >> 24) == 127;
    }
    in6_addr v6{};
    if (inet_pton(AF_INET6, text, &v6) == 1) {
        static constexpr std::uint8_t kLoopback6[16] = {0, 0, 0, 0, 0, 0, 0, 0,
                                                        0, 0, 0, 0, 0, 0, 0, 1};
        if (std::memcmp(v6.s6_addr, kLoopback6, 16) == 0) return true;
        static constexpr std::uint8_t kMappedPrefix[12] = {0, 0, 0, 0, 0,    0,
                                                           0, 0, 0, 0, 0xFF, 0xFF};
        return std::memcmp(v6.s6_addr, kMappedPrefix, 12) == 0 && v6.s6_addr[12] == 127;
    }
    return false;
}

WriteSafetyVerdict check_write_safety(const std::vector<Operation>& operations,
                                      std::string_view resolved_address, bool allow_writes) {
    WriteSafetyVerdict verdict;
    for (const Operation& op : operations) {
        if (!codec::is_write_function(op.function)) continue;
        const std::string_view fname = codec::function_name(op.function);
        verdict.write_operations.push_back(
            op.name.empty() ? fmt::format("0x{:02X} {}", op.function, fname)
                            : fmt::format("{} (0x{:02X} {})", op.name, op.function, fname));
    }
    if (verdict.write_operations.empty() || allow_writes || is_loopback_address(resolved_address)) {
        return verdict;
    }
    verdict.refusal = Error(
        ErrorCode::Refused,
        fmt::format("refusing to send write operations to {} (not a loopback address) without "
                    "allow_writes: {}. These change the device's state; set allow_writes "
                    "(--allow-writes) if that is intended.",
                    resolved_address, fmt::join(verdict.write_operations, ", ")));
    return verdict;
}

}  // namespace mbstorm::load
