#include "slave/faults.hpp"

#include <cmath>

namespace mbstorm::slave {

namespace {

std::uint64_t splitmix64(std::uint64_t& state) noexcept {
    std::uint64_t z = (state += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

std::uint64_t rotl(std::uint64_t x, int k) noexcept {
    return (x << k) | (x >> (64 - k));
}

// rate in [0, 1] -> threshold t such that P(draw < t) == rate for a uniform 64-bit draw.
std::uint64_t threshold(double rate) noexcept {
    if (rate <= 0.0) return 0;
    if (rate >= 1.0) return UINT64_MAX;
    return static_cast<std::uint64_t>(std::ldexp(rate, 64));
}

bool valid_rate(double r) noexcept {
    return r >= 0.0 && r <= 1.0;
}  // false for NaN too

}  // namespace

FastRng::FastRng(std::uint64_t seed) noexcept {
    std::uint64_t state = seed;
    for (auto& s : s_) s = splitmix64(state);
}

std::uint64_t FastRng::next() noexcept {
    const std::uint64_t result = rotl(s_[1] * 5, 7) * 9;
    const std::uint64_t t = s_[1] << 17;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = rotl(s_[3], 45);
    return result;
}

std::uint64_t FastRng::between(std::uint64_t lo, std::uint64_t hi) noexcept {
    const std::uint64_t span = hi - lo;
    if (span == UINT64_MAX) return next();
    // Multiply-shift range reduction: bias below 2^-64 * span, irrelevant here.
    const auto wide = static_cast<unsigned __int128>(next()) * (span + 1);
    return lo + static_cast<std::uint64_t>(wide >> 64);
}

bool FaultConfig::any() const noexcept {
    return delay.kind != DelayConfig::Kind::None || stall.period_ns != 0 || exception_rate > 0.0 ||
           drop_rate > 0.0 || no_answer_rate > 0.0;
}

Error validate(const FaultConfig& c) {
    if (!valid_rate(c.exception_rate))
        return Error(ErrorCode::InvalidInput, "exception rate must be between 0 and 1");
    if (!valid_rate(c.drop_rate))
        return Error(ErrorCode::InvalidInput, "drop rate must be between 0 and 1");
    if (!valid_rate(c.no_answer_rate))
        return Error(ErrorCode::InvalidInput, "no-answer rate must be between 0 and 1");
    if (c.exception_rate + c.drop_rate + c.no_answer_rate > 1.0 + 1e-12) {
        return Error(ErrorCode::InvalidInput,
                     "exception, drop and no-answer rates must add up to at most 1");
    }
    if (c.exception_rate > 0.0 && (static_cast<unsigned>(c.exception_code) == 0 ||
                                   static_cast<unsigned>(c.exception_code) > 0x7F)) {
        return Error(ErrorCode::InvalidInput, "injected exception code must be between 1 and 127");
    }
    if (c.delay.kind == DelayConfig::Kind::Uniform && c.delay.min_ns > c.delay.max_ns) {
        return Error(ErrorCode::InvalidInput, "uniform delay needs min <= max");
    }
    if (c.stall.period_ns != 0 && c.stall.duration_ns > c.stall.period_ns) {
        return Error(ErrorCode::InvalidInput, "stall duration must not exceed its period");
    }
    if (c.stall.period_ns == 0 && c.stall.duration_ns != 0) {
        return Error(ErrorCode::InvalidInput, "a stall duration needs a period");
    }
    return Error::none();
}

FaultInjector::FaultInjector(const FaultConfig& config, std::uint64_t stream,
                             std::uint64_t stall_origin_ns) noexcept
    : config_(config),
      rng_(config.seed ^ (stream * 0xd1342543de82ef95ULL)),
      stall_origin_ns_(stall_origin_ns),
      enabled_(config.any()) {
    // Cumulative thresholds; saturate so rounding can never wrap past the top.
    const auto add = [](std::uint64_t a, std::uint64_t b) {
        return a > UINT64_MAX - b ? UINT64_MAX : a + b;
    };
    drop_below_ = threshold(config.drop_rate);
    no_answer_below_ = add(drop_below_, threshold(config.no_answer_rate));
    exception_below_ = add(no_answer_below_, threshold(config.exception_rate));
}

std::uint64_t FaultInjector::draw_delay() noexcept {
    switch (config_.delay.kind) {
        case DelayConfig::Kind::None:
            return 0;
        case DelayConfig::Kind::Fixed:
            return config_.delay.fixed_ns;
        case DelayConfig::Kind::Uniform:
            return rng_.between(config_.delay.min_ns, config_.delay.max_ns);
        case DelayConfig::Kind::Exponential: {
            const double u = rng_.uniform();  // [0, 1): 1 - u is never 0
            return static_cast<std::uint64_t>(-std::log1p(-u) *
                                              static_cast<double>(config_.delay.mean_ns));
        }
    }
    return 0;
}

FaultDecision FaultInjector::decide() noexcept {
    FaultDecision d;
    if (!enabled_) return d;
    if (exception_below_ != 0) {
        const std::uint64_t draw = rng_.next();
        if (draw < drop_below_) {
            d.action = FaultDecision::Action::Drop;
            return d;
        }
        if (draw < no_answer_below_) {
            d.action = FaultDecision::Action::NoAnswer;
            return d;
        }
        if (draw < exception_below_) {
            d.action = FaultDecision::Action::Exception;
            d.exception = config_.exception_code;
        }
    }
    d.delay_ns = draw_delay();
    return d;
}

std::uint64_t FaultInjector::held_until(std::uint64_t now_ns) const noexcept {
    const StallConfig& s = config_.stall;
    if (s.period_ns == 0 || s.duration_ns == 0 || now_ns < stall_origin_ns_ + s.period_ns) {
        return now_ns;
    }
    const std::uint64_t phase = (now_ns - stall_origin_ns_) % s.period_ns;
    return phase < s.duration_ns ? now_ns - phase + s.duration_ns : now_ns;
}

}  // namespace mbstorm::slave
