// Proves the hot-path recording calls never touch the heap, by counting every global
// operator new in this test binary.
#include <gtest/gtest.h>

#include <random>

#include "../support/counting_allocator.hpp"
#include "stats/counters.hpp"
#include "stats/histogram.hpp"
#include "stats/interval_recorder.hpp"

namespace mbstorm::stats {
namespace {

TEST(Allocation, CountingHookSeesAllocations) {
    const auto before = mbstorm::testing::allocations();
    int* volatile p = new int(3);  // volatile: the compiler may not elide the pair
    delete p;
    EXPECT_GT(mbstorm::testing::allocations(), before);
}

TEST(Allocation, HistogramHotPathNeverAllocates) {
    Histogram h;
    Histogram other;
    other.record(12345);
    std::mt19937_64 rng(5);
    const auto before = mbstorm::testing::allocations();
    for (int i = 0; i < 1'000'000; ++i) h.record(1000 + rng() % 5'000'000'000ULL);
    h.record(Histogram::kOneHourNs * 2);  // saturated
    h.record_corrected(50'000'000, 1'000'000);
    h.record_corrected(2'000'000'000, 100);  // per-bucket back-fill path
    h.add(other);
    volatile auto p99 = h.value_at_percentile(99.0);
    volatile auto mean = h.mean();
    (void)p99;
    (void)mean;
    h.reset();
    EXPECT_EQ(mbstorm::testing::allocations(), before);
}

TEST(Allocation, CountersAndIntervalTickNeverAllocate) {
    IntervalTimeline timeline(1'000'000'000, 1, 64);
    IntervalRecorder rec(1'000'000'000);
    OutcomeCounters counters;
    const auto before = mbstorm::testing::allocations();
    for (std::uint64_t i = 0; i < 50'000; ++i) {
        const std::uint64_t now = i * 1'000'000;  // 50 simulated seconds
        rec.tick(now, timeline, 0);
        rec.record_latency(20'000 + i);
        rec.record_transaction(i % 7 == 0);
        counters.record(Outcome::Ok);
        counters.record_exception(static_cast<std::uint8_t>(i));
    }
    rec.flush(timeline, 0);
    timeline.finish();
    EXPECT_EQ(mbstorm::testing::allocations(), before);
    EXPECT_EQ(timeline.summaries().size(), 50u);
}

}  // namespace
}  // namespace mbstorm::stats
