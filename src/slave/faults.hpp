// Fault injection policy for the reference slave: what to configure, and a per-thread object
// that decides, request by request, whether to answer normally, late, wrongly or not at all.
// The server applies the decisions; nothing here does I/O or reads a clock.
#pragma once

#include <cstdint>
#include <string>

#include "codec/exception_code.hpp"
#include "util/error.hpp"

namespace mbstorm::slave {

struct DelayConfig {
    enum class Kind : std::uint8_t { None, Fixed, Uniform, Exponential };
    Kind kind = Kind::None;
    std::uint64_t fixed_ns = 0;  // Fixed
    std::uint64_t min_ns = 0;    // Uniform: [min_ns, max_ns]
    std::uint64_t max_ns = 0;
    std::uint64_t mean_ns = 0;  // Exponential
    bool operator==(const DelayConfig&) const = default;
};

// Every `period_ns` (the first one `period_ns` after the origin) all responses are held for
// `duration_ns`: a response due inside [k*period, k*period + duration) goes out at its end.
struct StallConfig {
    std::uint64_t duration_ns = 0;
    std::uint64_t period_ns = 0;  // 0: no stalls
    bool operator==(const StallConfig&) const = default;
};

// All off by default. The three rates are exclusive outcomes of one draw, so they must sum to
// at most 1: drop first, then no-answer, then exception; the rest is answered normally.
struct FaultConfig {
    DelayConfig delay;
    StallConfig stall;
    double exception_rate = 0.0;
    codec::ExceptionCode exception_code = codec::ExceptionCode::ServerDeviceFailure;
    double drop_rate = 0.0;       // close the connection instead of answering
    double no_answer_rate = 0.0;  // swallow the request silently
    std::uint64_t seed = 0x6d6273746f726dULL;

    bool any() const noexcept;
    bool operator==(const FaultConfig&) const = default;
};

// Success when `config` is usable, otherwise InvalidInput, one sentence saying what is wrong.
Error validate(const FaultConfig& config);

struct FaultDecision {
    enum class Action : std::uint8_t { Answer, Exception, Drop, NoAnswer };
    Action action = Action::Answer;
    codec::ExceptionCode exception = codec::ExceptionCode::None;  // Action::Exception only
    std::uint64_t delay_ns = 0;  // Answer and Exception: hold the response this long
};

// SplitMix64 seeding + xoshiro256** generator: a few ns per draw, reproducible per seed.
class FastRng {
  public:
    explicit FastRng(std::uint64_t seed) noexcept;
    std::uint64_t next() noexcept;
    // Uniform in [0, 1).
    double uniform() noexcept { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
    // Uniform in [lo, hi] (inclusive); requires lo <= hi.
    std::uint64_t between(std::uint64_t lo, std::uint64_t hi) noexcept;

  private:
    std::uint64_t s_[4];
};

// One per server thread (not thread-safe). Thread `stream` k of the same seed draws its own
// independent sequence, so a run is reproducible for a fixed seed and thread count.
class FaultInjector {
  public:
    FaultInjector(const FaultConfig& config, std::uint64_t stream = 0,
                  std::uint64_t stall_origin_ns = 0) noexcept;

    bool enabled() const noexcept { return enabled_; }
    FaultDecision decide() noexcept;
    // Monotonic time until which responses are held; `now_ns` itself when not stalled.
    std::uint64_t held_until(std::uint64_t now_ns) const noexcept;

  private:
    std::uint64_t draw_delay() noexcept;

    FaultConfig config_;
    FastRng rng_;
    std::uint64_t stall_origin_ns_;
    // Cumulative thresholds over the full 64-bit range for the single outcome draw.
    std::uint64_t drop_below_ = 0, no_answer_below_ = 0, exception_below_ = 0;
    bool enabled_ = false;
};

}  // namespace mbstorm::slave
