// The fuzzer's one source of randomness: splitmix64, so that a --seed replays a run exactly.
#pragma once

#include <cstdint>

namespace mbstorm::netfuzz {

class Rng {
  public:
    explicit Rng(std::uint64_t seed = 1) noexcept : state_(seed) {}

    std::uint64_t next() noexcept {
        std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return z ^ (z >> 31);
    }
    // Uniform in [0, n); n == 0 gives 0.
    std::uint32_t below(std::uint32_t n) noexcept {
        return n == 0 ? 0 : static_cast<std::uint32_t>((next() >> 32) * n >> 32);
    }
    bool chance(std::uint32_t one_in) noexcept { return below(one_in) == 0; }
    std::uint8_t byte() noexcept { return static_cast<std::uint8_t>(next()); }
    std::uint16_t u16() noexcept { return static_cast<std::uint16_t>(next()); }
    template <typename T, std::size_t N>
    const T& pick(const T (&items)[N]) noexcept {
        return items[below(N)];
    }

  private:
    std::uint64_t state_;
};

}  // namespace mbstorm::netfuzz
