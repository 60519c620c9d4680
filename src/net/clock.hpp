// Monotonic time in nanoseconds: the one clock every timeout, pacer and latency uses.
#pragma once

#include <cstdint>
#include <ctime>

namespace mbstorm::net {

inline std::int64_t now_ns() noexcept {
    timespec ts{};
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

inline constexpr std::int64_t kNsPerMs = 1'000'000;
inline constexpr std::int64_t kNsPerSec = 1'000'000'000;

// For io_uring timeouts, which take a __kernel_timespec.
inline constexpr void ns_to_timespec(std::int64_t ns, std::int64_t& sec, long long& nsec) noexcept {
    if (ns < 0) ns = 0;
    sec = ns / kNsPerSec;
    nsec = ns % kNsPerSec;
}

}  // namespace mbstorm::net
