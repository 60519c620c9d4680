// Log-linear latency histogram with HdrHistogram semantics.
//
// Unit: nanoseconds. Layout: lowest discernible value 1 ns, 3 significant decimal digits
// (2048 sub-buckets, 1024 per half), highest trackable value chosen at construction
// (default 1 hour). Every value in [0, highest] is stored with a relative error below
// 1/1024 (< 0.1%); values from 0 to 2047 ns are exact.
//
// The counts array is allocated once in the constructor; record() never allocates and has
// no branches apart from the clamp of oversized values (which are counted as saturated).
// The array is anonymous memory the kernel commits a page at a time on first write, so a
// histogram costs the pages its values touch (latencies within a few powers of two touch a
// handful of its 68 pages), not all 272 KB: a run keeping one per operation per thread and
// interval stays small. Not thread-safe: give each thread its own histogram and merge them
// with add().
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace mbstorm::stats {

class Histogram {
  public:
    static constexpr std::uint64_t kOneHourNs = 3'600'000'000'000ULL;
    static constexpr int kSignificantDigits = 3;
    static constexpr int kSubBucketHalfCountMagnitude = 10;
    static constexpr std::uint32_t kSubBucketHalfCount = 1u << kSubBucketHalfCountMagnitude;
    static constexpr std::uint32_t kSubBucketCount = 2 * kSubBucketHalfCount;  // 2048
    static constexpr std::uint64_t kSubBucketMask = kSubBucketCount - 1;

    // Tracks 0 .. 1 hour.
    Histogram() : Histogram(kOneHourNs) {}
    // highest_trackable_ns is raised to at least 2 * kSubBucketCount.
    explicit Histogram(std::uint64_t highest_trackable_ns);
    Histogram(const Histogram& other);
    Histogram& operator=(const Histogram& other);
    // A moved-from histogram may only be destroyed or assigned to.
    Histogram(Histogram&& other) noexcept = default;
    Histogram& operator=(Histogram&& other) noexcept = default;
    ~Histogram() = default;

    // Records one value (ns). Values above highest_trackable() are clamped to it and counted
    // in saturated_count(). Forced inline: once per answer in the engine, whose frame loop is
    // large enough for GCC to leave it out of line otherwise.
    [[gnu::always_inline]] void record(std::uint64_t value) noexcept { record_n(value, 1); }
    [[gnu::always_inline]] void record_n(std::uint64_t value, std::uint64_t count) noexcept {
        saturated_ += (value > highest_trackable_) ? count : 0;
        value = value > highest_trackable_ ? highest_trackable_ : value;
        counts_[counts_index(value)] += count;
        total_count_ += count;
        min_ = value < min_ ? value : min_;
        max_ = value > max_ ? value : max_;
    }
    // HdrHistogram's recordValueWithExpectedInterval: records value, then back-fills the
    // samples a closed-loop client failed to send while it waited (value - k*interval for
    // every k while that stays >= interval). Cost is bounded by counts_length(), never by
    // value / interval. expected_interval == 0 behaves like record().
    void record_corrected(std::uint64_t value, std::uint64_t expected_interval) noexcept;

    // Adds every count of other. Same layout: a plain array sum; otherwise values are
    // re-recorded (and clamped) at their highest-equivalent value.
    void add(const Histogram& other) noexcept;
    void reset() noexcept;
    // Adds count at counts index `index` (< counts_length()), as a decoder rebuilds a
    // histogram: min and max become the bucket's lowest and highest-equivalent values, as in
    // HdrHistogram after decoding, until narrow_extremes() says what was really recorded.
    void add_at_index(std::size_t index, std::uint64_t count) noexcept;
    // The exact smallest and largest values recorded, when known from elsewhere (a run's
    // summary): kept only where they lie within the recorded buckets.
    void narrow_extremes(std::uint64_t exact_min, std::uint64_t exact_max) noexcept;

    std::uint64_t total_count() const noexcept { return total_count_; }
    bool empty() const noexcept { return total_count_ == 0; }
    std::uint64_t saturated_count() const noexcept { return saturated_; }
    // Exact smallest / largest recorded value (after clamping); 0 when empty.
    std::uint64_t min() const noexcept { return total_count_ == 0 ? 0 : min_; }
    std::uint64_t max() const noexcept { return max_; }
    // HdrHistogram's mean and standard deviation: each count sits at its bucket's
    // median-equivalent value.
    double mean() const noexcept;
    double stddev() const noexcept;
    // HdrHistogram semantics: the highest-equivalent value of the smallest recorded value
    // whose cumulative count reaches ceil(p/100 * total) (nearest rank, at least 1), kept
    // within [min(), max()]: a bucket's upper edge may lie above the largest value recorded,
    // and a percentile above the max would be a number nobody measured.
    // p is clamped to [0, 100]; 0 when empty.
    std::uint64_t value_at_percentile(double percentile) const noexcept;
    // value clamped to [min(), max()] (the exact recorded extremes).
    std::uint64_t within_recorded(std::uint64_t value) const noexcept;

    std::uint64_t highest_trackable() const noexcept { return highest_trackable_; }
    std::uint32_t bucket_count() const noexcept { return bucket_count_; }
    std::size_t counts_length() const noexcept { return counts_length_; }
    std::uint64_t count_at_index(std::size_t index) const noexcept { return counts_[index]; }
    static std::uint64_t value_at_index(std::size_t index) noexcept;

    static std::uint64_t size_of_equivalent_range(std::uint64_t value) noexcept;
    static std::uint64_t lowest_equivalent(std::uint64_t value) noexcept;
    static std::uint64_t highest_equivalent(std::uint64_t value) noexcept {
        return lowest_equivalent(value) + size_of_equivalent_range(value) - 1;
    }
    static std::uint64_t median_equivalent(std::uint64_t value) noexcept {
        return lowest_equivalent(value) + (size_of_equivalent_range(value) >> 1);
    }

    static int bucket_index(std::uint64_t value) noexcept {
        // value | mask keeps everything below kSubBucketCount in bucket 0.
        return 64 - std::countl_zero(value | kSubBucketMask) - (kSubBucketHalfCountMagnitude + 1);
    }
    // The counts indices that can be non-zero, [first, last] (first > last when empty): the
    // buckets between min() and max(), so merges, resets and percentiles touch the recorded
    // range instead of all counts_length() counts (about 34,000 for one hour).
    std::size_t first_used_index() const noexcept;
    std::size_t last_used_index() const noexcept;

    // Bytes of the counts array the kernel has committed (resident pages), for tests and
    // memory accounting.
    std::size_t committed_bytes() const noexcept;

    static std::size_t counts_index(std::uint64_t value) noexcept {
        const int bucket = bucket_index(value);
        const auto sub_bucket = static_cast<std::size_t>(value >> bucket);
        return (static_cast<std::size_t>(bucket + 1) << kSubBucketHalfCountMagnitude) +
               (sub_bucket - kSubBucketHalfCount);
    }

  private:
    // Unmaps (or deletes, when the mapping failed and the heap served) a counts array.
    struct CountsRelease {
        std::size_t mapped_bytes = 0;  // 0: from new[]
        void operator()(std::uint64_t* counts) const noexcept;
    };
    using Counts = std::unique_ptr<std::uint64_t[], CountsRelease>;
    // Zeroed counts, committed page by page on first write.
    static Counts allocate_counts(std::size_t length);
    // Copies other's used range into this one's zeroed-elsewhere array.
    void copy_used_counts(const Histogram& other) noexcept;

    std::uint64_t highest_trackable_;
    std::uint32_t bucket_count_;
    std::size_t counts_length_;
    Counts counts_;
    std::uint64_t total_count_ = 0;
    std::uint64_t saturated_ = 0;
    std::uint64_t min_ = UINT64_MAX;
    std::uint64_t max_ = 0;
    // add_at_index put a count above max()'s bucket (a decoded histogram wider than this
    // one's trackable range): the used range is then every index.
    bool beyond_max_ = false;
};

// One step of HdrHistogram's percentile iteration.
struct PercentilePoint {
    std::uint64_t value = 0;        // highest-equivalent value reached, within [min, max] (ns)
    double percentile = 0.0;        // percentile level iterated to, 0..100
    std::uint64_t total_count = 0;  // cumulative count up to and including value
};

// HdrHistogram's percentile iterator: ticks_per_half_distance steps for every halving of
// the distance to 100%, then one last point at exactly 100%. Yields nothing when empty.
// The histogram must outlive the iterator and stay unchanged while iterating.
class PercentileIterator {
  public:
    explicit PercentileIterator(const Histogram& histogram,
                                std::uint32_t ticks_per_half_distance = 5);
    bool next(PercentilePoint& out) noexcept;

  private:
    const Histogram& histogram_;
    std::uint32_t ticks_per_half_distance_;
    std::size_t index_ = 0;
    bool started_ = false;
    bool seen_last_ = false;
    std::uint64_t cumulative_ = 0;
    std::uint64_t last_value_ = 0;
    double level_to_iterate_to_ = 0.0;
};

// Convenience: the whole iteration as a vector (allocates; not for the hot path).
std::vector<PercentilePoint> percentile_distribution(const Histogram& histogram,
                                                     std::uint32_t ticks_per_half_distance = 5);

}  // namespace mbstorm::stats
