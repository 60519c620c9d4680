// Fixed latency bucket boundaries for live metrics (Prometheus histograms). They never depend
// on the run, so the buckets of many runs or shards add up bucket by bucket.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace mbstorm::stats {

// Upper bounds (inclusive) in nanoseconds, 1-2.5-5 steps from 25 us to 10 s; one more bucket
// past the last holds everything slower (+Inf).
inline constexpr std::array<std::uint64_t, 18> kLatencyBucketBoundsNs = {
    25'000,      50'000,      100'000,       250'000,       500'000,       1'000'000,
    2'500'000,   5'000'000,   10'000'000,    25'000'000,    50'000'000,    100'000'000,
    250'000'000, 500'000'000, 1'000'000'000, 2'500'000'000, 5'000'000'000, 10'000'000'000};
inline constexpr std::size_t kLatencyBuckets = kLatencyBucketBoundsNs.size() + 1;

// Index of the bucket that holds a latency (the last one: above every bound).
constexpr std::size_t latency_bucket(std::uint64_t latency_ns) noexcept {
    std::size_t i = 0;
    while (i < kLatencyBucketBoundsNs.size() && latency_ns > kLatencyBucketBoundsNs[i]) ++i;
    return i;
}

}  // namespace mbstorm::stats
