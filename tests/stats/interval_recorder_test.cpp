#include "stats/interval_recorder.hpp"

#include <gtest/gtest.h>

#include <thread>
#include <vector>

namespace mbstorm::stats {
namespace {

constexpr std::uint64_t kSecond = 1'000'000'000;
constexpr std::uint64_t kOneMs = 1'000'000;

TEST(IntervalTimeline, SingleWorkerProducesOneSummaryPerInterval) {
    IntervalTimeline timeline(kSecond, 1, 100);
    IntervalRecorder rec(kSecond);
    // Interval 0: 3 transactions, one error; interval 1 empty; interval 2: one slow one.
    for (std::uint64_t t : {100 * kOneMs, 200 * kOneMs, 300 * kOneMs}) {
        rec.tick(t, timeline, 0);
        rec.record_latency(t);
        rec.record_transaction(t == 300 * kOneMs);
    }
    rec.tick(2 * kSecond + 5, timeline, 0);
    EXPECT_EQ(rec.current_index(), 2u);
    rec.record_latency(50 * kOneMs);
    rec.record_transaction(false);
    rec.flush(timeline, 0);
    timeline.finish();

    const auto s = timeline.summaries();
    ASSERT_EQ(s.size(), 3u);
    EXPECT_EQ(s[0].index, 0u);
    EXPECT_EQ(s[0].transactions, 3u);
    EXPECT_EQ(s[0].errors, 1u);
    EXPECT_EQ(s[0].max_ns, 300 * kOneMs);
    EXPECT_EQ(s[0].p50_ns, Histogram::highest_equivalent(200 * kOneMs));
    EXPECT_DOUBLE_EQ(s[0].transactions_per_second(), 3.0);
    EXPECT_EQ(s[1].transactions, 0u);  // gap filled, timeline stays continuous
    EXPECT_EQ(s[1].start_offset_ns, kSecond);
    EXPECT_EQ(s[2].transactions, 1u);
    EXPECT_EQ(s[2].max_ns, 50 * kOneMs);
    ASSERT_TRUE(timeline.latest().has_value());
    EXPECT_EQ(timeline.latest()->index, 2u);
}

TEST(IntervalRecorder, FoldsEveryIntervalIntoTheRunTotalOnce) {
    IntervalTimeline timeline(kSecond, 1, 100);
    IntervalRecorder rec(kSecond);
    Histogram total;
    rec.fold_into(&total);
    rec.record_latency(5 * kOneMs);
    rec.record_latency(7 * kOneMs);
    rec.tick(kSecond + 1, timeline, 0);  // interval 0 folded in
    EXPECT_EQ(total.total_count(), 2u);
    rec.record_latency(900 * kOneMs);
    rec.tick(kSecond + 2, timeline, 0);  // same interval: nothing folded yet
    EXPECT_EQ(total.total_count(), 2u);
    rec.flush(timeline, 0);
    rec.flush(timeline, 0);  // an empty interval adds nothing
    EXPECT_EQ(total.total_count(), 3u);
    EXPECT_EQ(total.min(), 5 * kOneMs);
    EXPECT_EQ(total.max(), 900 * kOneMs);
    EXPECT_EQ(total.value_at_percentile(50.0), Histogram::highest_equivalent(7 * kOneMs));
}

TEST(IntervalRecorder, FoldsEachTagIntoItsOwnTotalAndTheIntervalOnce) {
    IntervalTimeline timeline(kSecond, 1, 100);
    IntervalRecorder rec(kSecond, Histogram::kOneHourNs, 2);
    Histogram first, second;
    rec.fold_tags_into({&first, &second});
    rec.record_tagged(5 * kOneMs, 0);
    rec.record_tagged(7 * kOneMs, 1);
    rec.record_tagged(9 * kOneMs, 1);
    rec.tick(kSecond + 1, timeline, 0);
    EXPECT_EQ(first.total_count(), 1u);
    EXPECT_EQ(second.total_count(), 2u);
    rec.record_tagged(900 * kOneMs, 0);
    rec.flush(timeline, 0);
    rec.flush(timeline, 0);  // an empty interval adds nothing
    timeline.finish();
    EXPECT_EQ(first.total_count(), 2u);
    EXPECT_EQ(first.max(), 900 * kOneMs);
    EXPECT_EQ(second.total_count(), 2u);
    EXPECT_EQ(second.min(), 7 * kOneMs);
    const auto s = timeline.summaries();
    ASSERT_EQ(s.size(), 2u);
    EXPECT_EQ(s[0].latency_count, 3u);  // both tags, each latency once
    EXPECT_EQ(s[0].max_ns, 9 * kOneMs);
    EXPECT_EQ(s[1].latency_count, 1u);
    EXPECT_EQ(s[1].max_ns, 900 * kOneMs);
}

TEST(IntervalTimeline, WaitsForEveryWorkerBeforeSummarizing) {
    IntervalTimeline timeline(kSecond, 2, 100);
    IntervalRecorder a(kSecond), b(kSecond);
    a.record_latency(kOneMs);
    a.record_transaction(false);
    a.tick(kSecond, timeline, 0);  // worker 0 done with interval 0
    EXPECT_FALSE(timeline.latest().has_value());
    b.record_latency(9 * kOneMs);
    b.record_transaction(true);
    b.tick(kSecond + 1, timeline, 1);  // now both are done
    const auto latest = timeline.latest();
    ASSERT_TRUE(latest.has_value());
    EXPECT_EQ(latest->transactions, 2u);
    EXPECT_EQ(latest->errors, 1u);
    EXPECT_EQ(latest->max_ns, 9 * kOneMs);
    EXPECT_EQ(latest->latency_count, 2u);
}

TEST(IntervalTimeline, LaggingWorkerDoesNotHoldMemoryForever) {
    IntervalTimeline timeline(kSecond, 2, 100);
    IntervalRecorder fast(kSecond), slow(kSecond);
    for (std::uint64_t s = 1; s <= 10; ++s) {
        fast.record_transaction(false);
        fast.tick(s * kSecond, timeline, 0);
    }
    // The pending window is small, so old intervals were summarized without the slow worker.
    EXPECT_GE(timeline.summaries().size(), 6u);
    slow.record_transaction(false);
    slow.tick(10 * kSecond, timeline, 1);  // contributes interval 0, long summarized
    EXPECT_EQ(timeline.late_contributions(), 1u);
    timeline.finish();
    const auto s = timeline.summaries();
    ASSERT_EQ(s.size(), 10u);
    EXPECT_EQ(s[0].transactions, 2u);  // the late counts were still added
}

TEST(IntervalTimeline, CapsStoredIntervals) {
    IntervalTimeline timeline(kSecond, 1, 5);
    IntervalRecorder rec(kSecond);
    for (std::uint64_t s = 1; s <= 8; ++s) rec.tick(s * kSecond, timeline, 0);
    timeline.finish();
    EXPECT_EQ(timeline.summaries().size(), 5u);
    EXPECT_EQ(timeline.dropped_intervals(), 3u);
}

TEST(IntervalTimeline, ConcurrentWorkersLoseNoCounts) {
    constexpr std::uint32_t kWorkers = 4;
    constexpr std::uint64_t kIntervals = 20;
    constexpr std::uint64_t kPerInterval = 1000;
    IntervalTimeline timeline(kSecond, kWorkers, kIntervals + 2);
    std::vector<std::thread> threads;
    for (std::uint32_t w = 0; w < kWorkers; ++w) {
        threads.emplace_back([&, w] {
            IntervalRecorder rec(kSecond);
            for (std::uint64_t i = 0; i < kIntervals * kPerInterval; ++i) {
                // Simulated clock: kPerInterval transactions per second.
                rec.tick(i * (kSecond / kPerInterval), timeline, w);
                rec.record_latency(1000 + i % 5000);
                rec.record_transaction(i % 100 == 0);
            }
            rec.flush(timeline, w);
        });
    }
    for (auto& t : threads) t.join();
    timeline.finish();
    std::uint64_t total = 0, errors = 0;
    for (const auto& s : timeline.summaries()) {
        total += s.transactions;
        errors += s.errors;
    }
    EXPECT_EQ(total, kWorkers * kIntervals * kPerInterval);
    EXPECT_EQ(errors, kWorkers * kIntervals * kPerInterval / 100);
}

TEST(IntervalTimeline, KeptHistogramsHoldEveryIntervalByTagInOrder) {
    constexpr std::uint32_t kWorkers = 3;
    IntervalTimeline timeline(kSecond, kWorkers, 100);
    timeline.keep_histograms(2);
    std::vector<IntervalRecorder> recorders;
    for (std::uint32_t w = 0; w < kWorkers; ++w)
        recorders.emplace_back(kSecond, Histogram::kOneHourNs, timeline.tags());
    // Worker w records, in interval i, (w + 1) latencies of tag i % 2 and one of tag 1 - i % 2.
    for (std::uint64_t i = 0; i < 6; ++i) {
        for (std::uint32_t w = 0; w < kWorkers; ++w) {
            recorders[w].tick(i * kSecond + 1, timeline, w);
            for (std::uint32_t k = 0; k <= w; ++k)
                recorders[w].record_latency(1000 * (i + 1), static_cast<std::uint32_t>(i % 2));
            recorders[w].record_latency(7, static_cast<std::uint32_t>(1 - i % 2));
            recorders[w].record_transaction(false);
        }
    }
    for (std::uint32_t w = 0; w < kWorkers; ++w) recorders[w].flush(timeline, w);
    timeline.finish();
    std::vector<std::uint64_t> seen;
    timeline.drain_histograms([&](const IntervalHistograms& interval) {
        seen.push_back(interval.index);
        EXPECT_EQ(interval.start_offset_ns, interval.index * kSecond);
        EXPECT_EQ(interval.duration_ns, kSecond);
        ASSERT_EQ(interval.by_tag.size(), 2u);
        const auto main_tag = interval.index % 2;
        EXPECT_EQ(interval.by_tag[main_tag].total_count(), 1u + 2u + 3u);
        EXPECT_EQ(interval.by_tag[main_tag].max(), 1000 * (interval.index + 1));
        EXPECT_EQ(interval.by_tag[1 - main_tag].total_count(), kWorkers);
        EXPECT_EQ(interval.by_tag[1 - main_tag].max(), 7u);
        EXPECT_EQ(interval.all.total_count(), 6u + kWorkers);
    });
    EXPECT_EQ(seen, (std::vector<std::uint64_t>{0, 1, 2, 3, 4, 5}));
    // Drained once: nothing is handed over twice.
    std::size_t again = 0;
    timeline.drain_histograms([&](const IntervalHistograms&) { ++again; });
    EXPECT_EQ(again, 0u);
}

// Issue #31: run --hlog of a 1,000-operation scenario took 2.96 GB, a histogram per operation
// in each of the four pending intervals and each of the four spare sets. The per-operation
// histograms are held now only by the intervals in flight: drained as the engine drains them,
// a run of 20 intervals makes the two sets made up front and no more, and every interval
// still has every tag's histogram.
TEST(IntervalTimeline, OnlyIntervalsInFlightHoldTagHistograms) {
    constexpr std::uint32_t kTags = 8;
    IntervalTimeline timeline(kSecond, 2, 100);
    timeline.keep_histograms(kTags);
    std::vector<IntervalRecorder> recorders;
    for (std::uint32_t w = 0; w < 2; ++w)
        recorders.emplace_back(kSecond, Histogram::kOneHourNs, timeline.tags());
    std::size_t drained = 0;
    auto drain = [&](const IntervalHistograms& interval) {
        ++drained;
        ASSERT_EQ(interval.by_tag.size(), kTags);
        for (std::uint32_t t = 0; t < kTags; ++t)
            EXPECT_EQ(interval.by_tag[t].total_count(), 2u) << "interval " << interval.index;
    };
    for (std::uint64_t i = 0; i < 20; ++i) {
        for (std::uint32_t w = 0; w < 2; ++w) {
            recorders[w].tick(i * kSecond + 1, timeline, w);
            for (std::uint32_t t = 0; t < kTags; ++t) recorders[w].record_latency(1000 + t, t);
        }
        timeline.drain_histograms(drain);
    }
    for (std::uint32_t w = 0; w < 2; ++w) recorders[w].flush(timeline, w);
    timeline.finish();
    timeline.drain_histograms(drain);
    EXPECT_EQ(drained, 20u);
    EXPECT_EQ(timeline.tag_sets_made(), 2u);
}

}  // namespace
}  // namespace mbstorm::stats
