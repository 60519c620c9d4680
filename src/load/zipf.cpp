#include "load/zipf.hpp"

#include <algorithm>
#include <cmath>

namespace mbstorm::load {
namespace {

// log1p(x)/x and expm1(x)/x, continuous at 0 (where both are 1); these keep big_h stable
// for exponents near 1.
double log1p_over_x(double x) noexcept {
    return std::abs(x) > 1e-8 ? std::log1p(x) / x : 1 - x * (0.5 - x * (1.0 / 3 - 0.25 * x));
}
double expm1_over_x(double x) noexcept {
    return std::abs(x) > 1e-8 ? std::expm1(x) / x
                              : 1 + x * 0.5 * (1 + x * (1.0 / 3) * (1 + 0.25 * x));
}

}  // namespace

ZipfSampler::ZipfSampler(std::uint32_t n, double exponent) noexcept
    : n_(std::max<std::uint32_t>(n, 1)), exponent_(exponent) {
    h_integral_x1_ = big_h(1.5) - 1.0;
    h_integral_n_ = big_h(n_ + 0.5);
    squeeze_ = 2.0 - big_h_inverse(big_h(2.5) - h(2.0));
}

double ZipfSampler::h(double x) const noexcept {
    return std::exp(-exponent_ * std::log(x));
}

double ZipfSampler::big_h(double x) const noexcept {
    const double log_x = std::log(x);
    return expm1_over_x((1.0 - exponent_) * log_x) * log_x;
}

double ZipfSampler::big_h_inverse(double x) const noexcept {
    const double t = std::max(-1.0, x * (1.0 - exponent_));
    return std::exp(log1p_over_x(t) * x);
}

std::uint32_t ZipfSampler::sample(Rng& rng) const noexcept {
    if (n_ == 1) return 1;
    for (;;) {
        // u is uniform between H(n + 1/2) and H(3/2) - h(1).
        const double u = h_integral_n_ + rng.unit() * (h_integral_x1_ - h_integral_n_);
        const double x = big_h_inverse(u);
        double k = std::floor(x + 0.5);
        k = std::clamp(k, 1.0, static_cast<double>(n_));
        // Accept quickly inside the squeeze, otherwise compare with the exact bound.
        if (k - x <= squeeze_ || u >= big_h(k + 0.5) - h(k)) {
            return static_cast<std::uint32_t>(k);
        }
    }
}

}  // namespace mbstorm::load
