#include "load/pacer.hpp"

#include <algorithm>
#include <cmath>

namespace mbstorm::load {

namespace {
constexpr std::int64_t kNever = INT64_MAX / 2;  // paused: far enough that adding a gap is safe
}

Pacer::Pacer(double rate, Arrival arrival, std::uint64_t seed, std::int64_t start_ns) noexcept
    : arrival_(arrival), rng_(seed) {
    rate_ = rate;
    period_ns_ = rate > 0 ? 1e9 / rate : 0;
    origin_ns_ = start_ns;
    next_ns_ = rate > 0 ? start_ns : kNever;
}

std::int64_t Pacer::gap_ns() noexcept {
    if (arrival_ == Arrival::Even) return static_cast<std::int64_t>(std::llround(period_ns_));
    // Exponential gaps: a Poisson process of the same mean rate.
    return static_cast<std::int64_t>(-std::log(rng_.unit_open_zero()) * period_ns_);
}

void Pacer::set_rate(double rate, std::int64_t now_ns) noexcept {
    if (rate == rate_) return;
    rate_ = rate;
    if (rate <= 0) {
        period_ns_ = 0;
        next_ns_ = kNever;
        return;
    }
    period_ns_ = 1e9 / rate;
    const bool was_paused = next_ns_ >= kNever;
    next_ns_ = was_paused ? now_ns : std::min(next_ns_, now_ns + gap_ns());
    origin_ns_ = next_ns_;
    since_origin_ = 0;
}

void Pacer::advance() noexcept {
    ++count_;
    if (rate_ <= 0) return;
    ++since_origin_;
    if (arrival_ == Arrival::Even) {
        // From the origin each time, so rounding never accumulates into drift.
        next_ns_ = origin_ns_ + static_cast<std::int64_t>(std::llround(since_origin_ * period_ns_));
    } else {
        next_ns_ += gap_ns();
    }
}

}  // namespace mbstorm::load
