#include "load/pacer.hpp"

#include <cmath>

namespace mbstorm::load {

Pacer::Pacer(double rate, Arrival arrival, std::uint64_t seed, std::int64_t start_ns) noexcept
    : arrival_(arrival), rng_(seed) {
    set_rate(rate, start_ns);
}

void Pacer::set_rate(double rate, std::int64_t now_ns) noexcept {
    rate_ = rate > 0 ? rate : 1e-9;
    period_ns_ = 1e9 / rate_;
    origin_ns_ = now_ns;
    since_origin_ = 0;
    if (arrival_ == Arrival::Even) {
        next_ns_ = now_ns;
    } else {
        next_ns_ =
            now_ns + static_cast<std::int64_t>(-std::log(rng_.unit_open_zero()) * period_ns_);
    }
}

void Pacer::advance() noexcept {
    ++count_;
    ++since_origin_;
    if (arrival_ == Arrival::Even) {
        // From the origin each time, so rounding never accumulates into drift.
        next_ns_ = origin_ns_ + static_cast<std::int64_t>(std::llround(since_origin_ * period_ns_));
    } else {
        // Exponential gaps: a Poisson process of the same mean rate.
        next_ns_ += static_cast<std::int64_t>(-std::log(rng_.unit_open_zero()) * period_ns_);
    }
}

}  // namespace mbstorm::load
