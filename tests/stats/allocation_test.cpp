// Proves the hot-path recording calls never touch the heap, by counting every global
// operator new in this test binary.
#include <gtest/gtest.h>

#include <functional>
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

TEST(Allocation, KeptIntervalHistogramsNeverAllocateOnceWarm) {
    // An interval log keeps every interval's histograms: recording, handing them over and
    // draining them reuses a pool (the drain runs every few intervals, as the engine's does).
    IntervalTimeline timeline(1'000'000'000, 1, 64);
    timeline.keep_histograms(2);
    IntervalRecorder rec(1'000'000'000, Histogram::kOneHourNs, timeline.tags());
    std::uint64_t drained = 0, counted = 0;
    const std::function<void(const IntervalHistograms&)> drain =
        [&](const IntervalHistograms& interval) {
            ++drained;
            counted += interval.all.total_count();
        };
    const auto before = mbstorm::testing::allocations();
    for (std::uint64_t i = 0; i < 50'000; ++i) {
        const std::uint64_t now = i * 1'000'000;  // 50 simulated seconds
        rec.tick(now, timeline, 0);
        rec.record_latency(20'000 + i, static_cast<std::uint32_t>(i % 2));
        rec.record_transaction(false);
        if (i % 2000 == 0) timeline.drain_histograms(drain);
    }
    rec.flush(timeline, 0);
    timeline.finish();
    timeline.drain_histograms(drain);
    EXPECT_EQ(mbstorm::testing::allocations(), before);
    EXPECT_EQ(drained, 50u);
    EXPECT_EQ(counted, 50'000u);
}

}  // namespace
}  // namespace mbstorm::stats
