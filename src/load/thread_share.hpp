// How the engine splits a total (connections, transactions) over its threads: as evenly as
// possible, the first `total % threads` threads taking one more.
#pragma once

#include <cstdint>

namespace mbstorm::load {

constexpr std::uint64_t thread_share(std::uint64_t total, std::uint32_t threads,
                                     std::uint32_t index) noexcept {
    return threads == 0 ? 0 : total / threads + (index < total % threads ? 1 : 0);
}

}  // namespace mbstorm::load
