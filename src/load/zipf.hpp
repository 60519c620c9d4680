// Zipf-distributed ranks 1..n in O(1) time and memory: rejection-inversion sampling
// (Hoermann & Derflinger, 1996). P(k) ~ 1 / k^exponent, exponent > 0 (1 included).
#pragma once

#include <cstdint>

#include "load/rng.hpp"

namespace mbstorm::load {

class ZipfSampler {
  public:
    ZipfSampler() = default;
    ZipfSampler(std::uint32_t n, double exponent) noexcept;

    // A rank in 1..n; rank 1 is the most frequent.
    std::uint32_t sample(Rng& rng) const noexcept;

    std::uint32_t size() const noexcept { return n_; }

  private:
    double h(double x) const noexcept;      // the density 1/x^s
    double big_h(double x) const noexcept;  // an antiderivative of h
    double big_h_inverse(double x) const noexcept;

    std::uint32_t n_ = 1;
    double exponent_ = 1;
    double h_integral_x1_ = 0;
    double h_integral_n_ = 0;
    double squeeze_ = 0;
};

}  // namespace mbstorm::load
