#include "stats/histogram.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace mbstorm::stats {
namespace {

constexpr std::uint64_t kUs = 1'000;
constexpr std::uint64_t kMs = 1'000'000;
constexpr std::uint64_t kS = 1'000'000'000;

// Nearest-rank percentile of the raw samples: the reference the histogram must match.
std::uint64_t exact_percentile(const std::vector<std::uint64_t>& sorted, double p) {
    const double exact = p / 100.0 * static_cast<double>(sorted.size());
    const double nearest = std::round(exact);
    double rank =
        std::fabs(exact - nearest) <= 1e-9 * std::max(1.0, exact) ? nearest : std::ceil(exact);
    rank = std::clamp(rank, 1.0, static_cast<double>(sorted.size()));
    return sorted[static_cast<std::size_t>(rank) - 1];
}

void expect_matches_samples(std::vector<std::uint64_t> samples, const char* what) {
    SCOPED_TRACE(what);
    Histogram h;
    for (auto v : samples) h.record(v);
    std::sort(samples.begin(), samples.end());
    ASSERT_EQ(h.total_count(), samples.size());
    EXPECT_EQ(h.min(), samples.front());
    EXPECT_EQ(h.max(), samples.back());
    for (double p :
         {0.0, 1.0, 10.0, 25.0, 50.0, 75.0, 90.0, 95.0, 99.0, 99.9, 99.99, 99.999, 100.0}) {
        const std::uint64_t exact = exact_percentile(samples, p);
        const std::uint64_t got = h.value_at_percentile(p);
        // HdrHistogram semantics: the highest value equivalent to the exact sample, but never
        // above the recorded max...
        EXPECT_EQ(got, std::min(Histogram::highest_equivalent(exact), samples.back())) << "p" << p;
        // ...which is within 3 significant digits of it.
        ASSERT_GE(got, exact) << "p" << p;
        EXPECT_LE(static_cast<double>(got - exact), 0.001 * static_cast<double>(exact))
            << "p" << p << " exact " << exact << " got " << got;
    }
    long double sum = 0;
    for (auto v : samples) sum += static_cast<long double>(v);
    const double mean = static_cast<double>(sum / samples.size());
    EXPECT_NEAR(h.mean(), mean, 0.001 * mean);
}

TEST(Histogram, LayoutCoversOneHourWithThreeDigits) {
    Histogram h;
    EXPECT_EQ(h.highest_trackable(), Histogram::kOneHourNs);
    EXPECT_EQ(Histogram::kSubBucketCount, 2048u);
    EXPECT_EQ(h.bucket_count(), 32u);
    EXPECT_EQ(h.counts_length(), 33u * 1024u);
    EXPECT_LT(Histogram::counts_index(Histogram::kOneHourNs), h.counts_length());
    // Values below the sub-bucket count are exact.
    for (std::uint64_t v = 0; v < 2048; ++v) {
        ASSERT_EQ(Histogram::lowest_equivalent(v), v);
        ASSERT_EQ(Histogram::highest_equivalent(v), v);
    }
}

TEST(Histogram, EquivalentRangesAreWithinOneThousandth) {
    std::mt19937_64 rng(7);
    for (int i = 0; i < 200000; ++i) {
        const std::uint64_t v = 1000 + rng() % Histogram::kOneHourNs;
        const std::uint64_t lo = Histogram::lowest_equivalent(v);
        const std::uint64_t hi = Histogram::highest_equivalent(v);
        ASSERT_LE(lo, v);
        ASSERT_GE(hi, v);
        ASSERT_LT(static_cast<double>(hi - lo + 1), static_cast<double>(v) / 1000.0 + 1.0);
        ASSERT_EQ(Histogram::value_at_index(Histogram::counts_index(v)), lo);
    }
}

TEST(Histogram, UniformDistribution) {
    std::mt19937_64 rng(1);
    std::uniform_int_distribution<std::uint64_t> dist(kUs, kS);
    std::vector<std::uint64_t> samples(200000);
    for (auto& v : samples) v = dist(rng);
    expect_matches_samples(samples, "uniform 1us..1s");
}

TEST(Histogram, ExponentialDistribution) {
    std::mt19937_64 rng(2);
    std::exponential_distribution<double> dist(1.0 / kMs);
    std::vector<std::uint64_t> samples(200000);
    for (auto& v : samples) v = kUs + static_cast<std::uint64_t>(dist(rng));
    expect_matches_samples(samples, "exponential mean 1ms");
}

TEST(Histogram, BimodalDistribution) {
    std::mt19937_64 rng(3);
    std::normal_distribution<double> fast(200.0 * kUs, 20.0 * kUs);
    std::normal_distribution<double> slow(50.0 * kMs, 5.0 * kMs);
    std::vector<std::uint64_t> samples(200000);
    for (std::size_t i = 0; i < samples.size(); ++i) {
        const double v = (i % 100 < 97) ? fast(rng) : slow(rng);
        samples[i] = static_cast<std::uint64_t>(std::max(v, 1000.0));
    }
    expect_matches_samples(samples, "bimodal 200us / 50ms");
}

TEST(Histogram, ValuesAtBucketEdges) {
    std::vector<std::uint64_t> samples;
    for (int shift = 0; shift < 31; ++shift) {
        for (std::uint64_t sub : {1024u, 1025u, 2047u, 2048u}) {
            const std::uint64_t edge = sub << shift;
            for (std::uint64_t v : {edge - 1, edge, edge + 1}) {
                if (v >= kUs && v <= Histogram::kOneHourNs) samples.push_back(v);
            }
        }
    }
    // Repeat with multiplicities so percentiles land on different edges.
    std::vector<std::uint64_t> weighted;
    for (std::size_t i = 0; i < samples.size(); ++i)
        weighted.insert(weighted.end(), 1 + i % 7, samples[i]);
    expect_matches_samples(weighted, "bucket edges");
}

TEST(Histogram, ExtremesOneMicrosecondAndOneHour) {
    std::vector<std::uint64_t> samples;
    samples.insert(samples.end(), 1000, kUs);
    samples.insert(samples.end(), 10, Histogram::kOneHourNs);
    expect_matches_samples(samples, "1us and 1h");
    Histogram h;
    h.record(kUs);
    h.record(Histogram::kOneHourNs);
    EXPECT_EQ(h.value_at_percentile(0), kUs);  // 1000 < 2048: exact
    EXPECT_EQ(h.saturated_count(), 0u);
    EXPECT_EQ(h.max(), Histogram::kOneHourNs);
}

TEST(Histogram, ClampsAndCountsSaturatedValues) {
    Histogram h(kS);
    h.record(5 * kS);
    h.record(kMs);
    EXPECT_EQ(h.total_count(), 2u);
    EXPECT_EQ(h.saturated_count(), 1u);
    EXPECT_EQ(h.max(), kS);
    EXPECT_EQ(h.value_at_percentile(100), kS);
}

// 41 ms sits in a 32.768-us-wide bucket whose upper edge is 41.025 ms: the bucket edge used to
// be reported as p99.999 and p100, above the max of 41.000 ms.
TEST(Histogram, PercentilesStayWithinMinAndMax) {
    Histogram h;
    for (int i = 0; i < 1000; ++i) h.record(3 * kMs + 1);
    h.record(41 * kMs);
    ASSERT_GT(Histogram::highest_equivalent(41 * kMs), 41 * kMs);
    for (double p : {0.0, 50.0, 99.9, 99.99, 99.999, 100.0}) {
        EXPECT_LE(h.value_at_percentile(p), h.max()) << "p" << p;
        EXPECT_GE(h.value_at_percentile(p), h.min()) << "p" << p;
    }
    EXPECT_EQ(h.value_at_percentile(100), 41 * kMs);
    for (const auto& point : percentile_distribution(h)) {
        EXPECT_LE(point.value, h.max()) << "percentile " << point.percentile;
        EXPECT_GE(point.value, h.min()) << "percentile " << point.percentile;
    }
    // A single sample: every percentile is that sample, exactly.
    Histogram one;
    one.record(41 * kMs);
    EXPECT_EQ(one.value_at_percentile(50), 41 * kMs);
    EXPECT_EQ(one.value_at_percentile(99.999), 41 * kMs);
}

TEST(Histogram, EmptyHistogram) {
    Histogram h;
    EXPECT_TRUE(h.empty());
    EXPECT_EQ(h.min(), 0u);
    EXPECT_EQ(h.max(), 0u);
    EXPECT_EQ(h.value_at_percentile(99), 0u);
    EXPECT_EQ(h.mean(), 0.0);
    EXPECT_EQ(h.stddev(), 0.0);
    EXPECT_TRUE(percentile_distribution(h).empty());
}

TEST(Histogram, MeanAndStddevOfConstantAndTwoPoints) {
    Histogram h;
    for (int i = 0; i < 100; ++i) h.record(1500);
    EXPECT_DOUBLE_EQ(h.mean(), 1500.0);
    EXPECT_DOUBLE_EQ(h.stddev(), 0.0);
    h.reset();
    h.record(1000);
    h.record(2000);
    EXPECT_DOUBLE_EQ(h.mean(), 1500.0);
    EXPECT_DOUBLE_EQ(h.stddev(), 500.0);
}

void expect_same_counts(const Histogram& a, const Histogram& b) {
    ASSERT_EQ(a.counts_length(), b.counts_length());
    for (std::size_t i = 0; i < a.counts_length(); ++i) {
        ASSERT_EQ(a.count_at_index(i), b.count_at_index(i)) << "index " << i;
    }
    EXPECT_EQ(a.total_count(), b.total_count());
    EXPECT_EQ(a.min(), b.min());
    EXPECT_EQ(a.max(), b.max());
}

TEST(Histogram, MergeEqualsRecordingEverythingInOne) {
    std::mt19937_64 rng(4);
    std::uniform_int_distribution<std::uint64_t> dist(kUs, 10 * kS);
    Histogram all, part1, part2, part3;
    for (int i = 0; i < 100000; ++i) {
        const auto v = dist(rng);
        all.record(v);
        (i % 3 == 0 ? part1 : i % 3 == 1 ? part2 : part3).record(v);
    }
    Histogram merged;
    merged.add(part1);
    merged.add(part2);
    merged.add(part3);
    expect_same_counts(merged, all);
    EXPECT_EQ(merged.value_at_percentile(99.9), all.value_at_percentile(99.9));
}

TEST(Histogram, MergeAcrossDifferentRanges) {
    Histogram small(kS);
    small.record(kMs);
    small.record(2 * kS);  // saturated in small
    Histogram big;
    big.record(10 * kS);
    big.record(3 * kUs);

    Histogram into_big;
    into_big.add(small);
    EXPECT_EQ(into_big.total_count(), 2u);
    EXPECT_EQ(into_big.saturated_count(), 1u);
    EXPECT_EQ(into_big.max(), kS);

    Histogram into_small(kS);
    into_small.add(big);
    EXPECT_EQ(into_small.total_count(), 2u);
    EXPECT_EQ(into_small.saturated_count(), 1u);  // 10 s clamped to 1 s
    EXPECT_EQ(into_small.min(), 3 * kUs);
    EXPECT_EQ(into_small.max(), kS);
}

TEST(Histogram, ResetClearsEverything) {
    Histogram h;
    for (std::uint64_t v = kUs; v < kS; v *= 3) h.record(v);
    h.record(2 * Histogram::kOneHourNs);
    h.reset();
    EXPECT_EQ(h.total_count(), 0u);
    EXPECT_EQ(h.saturated_count(), 0u);
    for (std::size_t i = 0; i < h.counts_length(); ++i) ASSERT_EQ(h.count_at_index(i), 0u);
    h.record(7 * kUs);
    EXPECT_EQ(h.min(), 7 * kUs);
    EXPECT_EQ(h.max(), 7 * kUs);
}

TEST(Histogram, ResetClearsACountDecodedAboveTheTrackableRange) {
    // A decoded histogram can hold a count past max()'s bucket (add_at_index of an index
    // beyond this histogram's highest trackable value): merges and resets must still see it.
    Histogram h(1'000'000);
    const std::size_t top = h.counts_length() - 1;
    h.add_at_index(top, 3);
    ASSERT_GT(top, Histogram::counts_index(h.max()));
    Histogram merged(1'000'000);
    merged.add(h);
    EXPECT_EQ(merged.count_at_index(top), 3u);
    h.reset();
    for (std::size_t i = 0; i < h.counts_length(); ++i) ASSERT_EQ(h.count_at_index(i), 0u);
}

TEST(Histogram, ReusedAfterResetGivesTheSameAnswersAsAFreshOne) {
    // Resets clear only the used range; a histogram reused over many intervals (the interval
    // recorder) must answer exactly like a new one.
    Histogram reused;
    for (std::uint64_t v = kUs; v < kS; v *= 7) reused.record(v);
    reused.reset();
    Histogram fresh;
    for (std::uint64_t v : {3 * kUs, 40 * kUs, 41 * kUs, 900 * kUs}) {
        reused.record(v);
        fresh.record(v);
    }
    for (double p : {0.0, 25.0, 50.0, 99.0, 100.0})
        EXPECT_EQ(reused.value_at_percentile(p), fresh.value_at_percentile(p)) << p;
    EXPECT_DOUBLE_EQ(reused.mean(), fresh.mean());
    EXPECT_DOUBLE_EQ(reused.stddev(), fresh.stddev());
    for (std::size_t i = 0; i < fresh.counts_length(); ++i)
        ASSERT_EQ(reused.count_at_index(i), fresh.count_at_index(i)) << i;
}

TEST(Histogram, CopyIsDeep) {
    Histogram a;
    a.record(5 * kMs);
    Histogram b = a;
    b.record(6 * kMs);
    EXPECT_EQ(a.total_count(), 1u);
    EXPECT_EQ(b.total_count(), 2u);
    Histogram c(kS);
    c = b;
    EXPECT_EQ(c.highest_trackable(), b.highest_trackable());
    expect_same_counts(c, b);
}

Histogram naive_corrected(std::uint64_t value, std::uint64_t interval) {
    Histogram h;
    h.record(value);
    if (interval == 0) return h;
    for (std::uint64_t missing = value - interval; value > interval && missing >= interval;
         missing -= interval) {
        h.record(missing);
    }
    return h;
}

TEST(Histogram, CoordinatedOmissionCorrectionMatchesHdrLoop) {
    for (auto [value, interval] : std::vector<std::pair<std::uint64_t, std::uint64_t>>{
             {10 * kMs, kMs},  // few back-filled samples: the plain loop
             {kMs, 2 * kMs},   // below the interval: nothing back-filled
             {3 * kMs, kMs},   // exactly divisible
             {kS + 17, 997},   // ~1M back-filled samples: the per-bucket path
             {40 * kMs, 1234}}) {
        SCOPED_TRACE(::testing::Message() << value << "/" << interval);
        Histogram fast;
        fast.record_corrected(value, interval);
        expect_same_counts(fast, naive_corrected(value, interval));
    }
    Histogram plain;
    plain.record_corrected(5 * kMs, 0);
    EXPECT_EQ(plain.total_count(), 1u);
}

TEST(PercentileIterator, FollowsHdrHistogramTicks) {
    Histogram h;
    for (std::uint64_t v = 1; v <= 10000; ++v) h.record(v * kUs);
    const auto points = percentile_distribution(h, 5);
    ASSERT_GT(points.size(), 10u);
    EXPECT_EQ(points.front().percentile, 0.0);
    EXPECT_EQ(points.front().value, kUs);
    // 5 ticks per half distance: 0, 10, 20, 30, 40, 50, then 55, 60, ...
    EXPECT_DOUBLE_EQ(points[1].percentile, 10.0);
    EXPECT_DOUBLE_EQ(points[5].percentile, 50.0);
    EXPECT_DOUBLE_EQ(points[6].percentile, 55.0);
    EXPECT_DOUBLE_EQ(points[10].percentile, 75.0);
    EXPECT_DOUBLE_EQ(points[11].percentile, 77.5);
    for (std::size_t i = 1; i < points.size(); ++i) {
        ASSERT_GE(points[i].percentile, points[i - 1].percentile);
        ASSERT_GE(points[i].value, points[i - 1].value);
        ASSERT_GE(points[i].total_count, points[i - 1].total_count);
    }
    for (std::size_t i = 0; i + 1 < points.size(); ++i) {
        ASSERT_EQ(points[i].value, h.value_at_percentile(points[i].percentile))
            << "percentile " << points[i].percentile;
    }
    EXPECT_EQ(points.back().percentile, 100.0);
    EXPECT_EQ(points.back().total_count, 10000u);
    EXPECT_EQ(points.back().value, 10000 * kUs);  // the max, not its bucket's upper edge
}

TEST(PercentileIterator, SingleValue) {
    Histogram h;
    h.record(1234);
    const auto points = percentile_distribution(h);
    ASSERT_EQ(points.size(), 2u);
    EXPECT_EQ(points[0].percentile, 0.0);
    EXPECT_EQ(points[1].percentile, 100.0);
    EXPECT_EQ(points[0].value, 1234u);
    EXPECT_EQ(points[1].value, 1234u);
}

// A run keeps one histogram per operation per thread (and per interval with --hlog): each must
// cost the pages its values touch, not the 272 KB a one-hour layout spans (issue #31: a
// 1,000-operation scenario took 1.3 GB with --hlog).
TEST(HistogramMemory, LatenciesWithinTwoPowersOfTwoCommitAFewPages) {
    Histogram histogram;
    const std::size_t whole = histogram.counts_length() * sizeof(std::uint64_t);
    EXPECT_LE(histogram.committed_bytes(), 4096u) << "a new histogram commits next to nothing";
    for (std::uint64_t ns = 100'000; ns < 200'000; ns += 7) histogram.record(ns);
    EXPECT_LE(histogram.committed_bytes(), 4u * 4096) << "of " << whole << " bytes";
    EXPECT_EQ(histogram.min(), 100'000u);
    EXPECT_EQ(histogram.total_count(), (200'000u - 100'000u + 6) / 7);
}

TEST(HistogramMemory, ACopyCommitsOnlyTheRangeInUse) {
    Histogram original;
    original.record(150'000);
    original.record(151'000);
    const Histogram copy(original);
    EXPECT_LE(copy.committed_bytes(), 2u * 4096);
    Histogram assigned;
    assigned.record(3'000'000'000);  // a different range, cleared by the assignment
    assigned = original;
    EXPECT_LE(assigned.committed_bytes(), 3u * 4096);
    for (const Histogram* h : std::vector<const Histogram*>{&copy, &assigned}) {
        EXPECT_EQ(h->total_count(), 2u);
        EXPECT_EQ(h->min(), 150'000u);
        EXPECT_EQ(h->max(), 151'000u);
        EXPECT_EQ(h->value_at_percentile(100.0), 151'000u);
        EXPECT_EQ(h->count_at_index(Histogram::counts_index(3'000'000'000)), 0u);
    }
}

}  // namespace
}  // namespace mbstorm::stats
