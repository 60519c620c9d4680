#include "stats/histogram.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include <sys/mman.h>
#include <unistd.h>

namespace mbstorm::stats {
namespace {

constexpr std::uint64_t kMaxHighestTrackable = std::uint64_t{1} << 62;

std::uint32_t buckets_to_cover(std::uint64_t value) noexcept {
    std::uint64_t smallest_untrackable = Histogram::kSubBucketCount;
    std::uint32_t buckets = 1;
    while (smallest_untrackable <= value) {
        smallest_untrackable <<= 1;
        ++buckets;
    }
    return buckets;
}

// Nearest-rank count for a percentile: ceil(p/100 * total), treating values within
// floating-point noise of an integer as that integer (0.999 * 1000 must give 999).
std::uint64_t rank_for_percentile(double percentile, std::uint64_t total) noexcept {
    const double p = std::clamp(percentile, 0.0, 100.0);
    const double exact = p / 100.0 * static_cast<double>(total);
    const double nearest = std::round(exact);
    double rank =
        std::fabs(exact - nearest) <= 1e-9 * std::max(1.0, exact) ? nearest : std::ceil(exact);
    rank = std::clamp(rank, 1.0, static_cast<double>(total));
    return static_cast<std::uint64_t>(rank);
}

}  // namespace

Histogram::Counts Histogram::allocate_counts(std::size_t length) {
    const std::size_t bytes = length * sizeof(std::uint64_t);
    const auto page = static_cast<std::size_t>(::sysconf(_SC_PAGESIZE));
    const std::size_t mapped = (bytes + page - 1) / page * page;
    void* memory =
        ::mmap(nullptr, mapped, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (memory == MAP_FAILED) return Counts(new std::uint64_t[length](), CountsRelease{});
    // A huge page would commit 2 MB on the first write: the point is to commit little.
    ::madvise(memory, mapped, MADV_NOHUGEPAGE);
    return Counts(static_cast<std::uint64_t*>(memory), CountsRelease{mapped});
}

void Histogram::CountsRelease::operator()(std::uint64_t* counts) const noexcept {
    if (mapped_bytes == 0) {
        delete[] counts;
    } else {
        ::munmap(counts, mapped_bytes);
    }
}

std::size_t Histogram::committed_bytes() const noexcept {
    const std::size_t mapped = counts_.get_deleter().mapped_bytes;
    if (mapped == 0) return counts_length_ * sizeof(std::uint64_t);
    const auto page = static_cast<std::size_t>(::sysconf(_SC_PAGESIZE));
    std::vector<unsigned char> resident(mapped / page);
    if (::mincore(counts_.get(), mapped, resident.data()) != 0) return mapped;
    const auto pages = std::count_if(resident.begin(), resident.end(),
                                     [](unsigned char flags) { return (flags & 1) != 0; });
    return static_cast<std::size_t>(pages) * page;
}

Histogram::Histogram(std::uint64_t highest_trackable_ns)
    : highest_trackable_(std::clamp<std::uint64_t>(highest_trackable_ns, 2 * kSubBucketCount,
                                                   kMaxHighestTrackable)),
      bucket_count_(buckets_to_cover(highest_trackable_)),
      counts_length_(static_cast<std::size_t>(bucket_count_ + 1) * kSubBucketHalfCount),
      counts_(allocate_counts(counts_length_)) {}

Histogram::Histogram(const Histogram& other)
    : highest_trackable_(other.highest_trackable_),
      bucket_count_(other.bucket_count_),
      counts_length_(other.counts_length_),
      counts_(allocate_counts(counts_length_)) {
    copy_used_counts(other);
}

Histogram& Histogram::operator=(const Histogram& other) {
    if (this == &other) return *this;
    if (counts_ && counts_length_ == other.counts_length_) {
        reset();  // zeroes the range in use, so that all of the array is zero
    } else {
        counts_ = allocate_counts(other.counts_length_);
    }
    highest_trackable_ = other.highest_trackable_;
    bucket_count_ = other.bucket_count_;
    counts_length_ = other.counts_length_;
    copy_used_counts(other);
    return *this;
}

void Histogram::copy_used_counts(const Histogram& other) noexcept {
    // Only the used range is copied: outside it both arrays are zero, and copying the zeros
    // would commit every page.
    const std::size_t first = other.first_used_index();
    const std::size_t last = other.last_used_index();
    if (first <= last) {
        std::memcpy(counts_.get() + first, other.counts_.get() + first,
                    (last - first + 1) * sizeof(std::uint64_t));
    }
    total_count_ = other.total_count_;
    saturated_ = other.saturated_;
    min_ = other.min_;
    max_ = other.max_;
    beyond_max_ = other.beyond_max_;
}

std::uint64_t Histogram::value_at_index(std::size_t index) noexcept {
    int bucket = static_cast<int>(index >> kSubBucketHalfCountMagnitude) - 1;
    std::uint64_t sub_bucket = (index & (kSubBucketHalfCount - 1)) + kSubBucketHalfCount;
    if (bucket < 0) {
        sub_bucket -= kSubBucketHalfCount;
        bucket = 0;
    }
    return sub_bucket << bucket;
}

std::uint64_t Histogram::size_of_equivalent_range(std::uint64_t value) noexcept {
    const int bucket = bucket_index(value);
    const std::uint64_t sub_bucket = value >> bucket;
    const int adjusted = sub_bucket >= kSubBucketCount ? bucket + 1 : bucket;
    return std::uint64_t{1} << adjusted;
}

std::uint64_t Histogram::lowest_equivalent(std::uint64_t value) noexcept {
    const int bucket = bucket_index(value);
    return (value >> bucket) << bucket;
}

void Histogram::record_corrected(std::uint64_t value, std::uint64_t expected_interval) noexcept {
    record(value);
    const std::uint64_t v = std::min(value, highest_trackable_);
    if (expected_interval == 0 || v <= expected_interval) return;

    // Missing samples are v - k*I for k = 1..k_last (all >= I).
    const std::uint64_t interval = expected_interval;
    const std::uint64_t k_last = v / interval - 1;
    if (k_last == 0) return;
    if (k_last <= counts_length_) {
        for (std::uint64_t k = 1; k <= k_last; ++k) record(v - k * interval);
        return;
    }
    // Too many samples to record one by one: count how many land in each bucket instead,
    // so the cost stays bounded by the number of buckets between I and v - I.
    const std::uint64_t lowest_missing = v - k_last * interval;
    const std::uint64_t highest_missing = v - interval;
    const std::size_t first = counts_index(lowest_missing);
    const std::size_t last = counts_index(highest_missing);
    for (std::size_t i = first; i <= last; ++i) {
        const std::uint64_t lo = std::max(value_at_index(i), lowest_missing);
        const std::uint64_t hi = std::min(highest_equivalent(value_at_index(i)), highest_missing);
        if (lo > hi) continue;
        // k such that lo <= v - k*I <= hi  <=>  (v - hi)/I <= k <= (v - lo)/I
        const std::uint64_t k_min = (v - hi + interval - 1) / interval;
        const std::uint64_t k_max = (v - lo) / interval;
        if (k_max < k_min) continue;
        const std::uint64_t n = k_max - k_min + 1;
        counts_[i] += n;
        total_count_ += n;
    }
    min_ = std::min(min_, lowest_missing);
}

void Histogram::add(const Histogram& other) noexcept {
    if (other.total_count_ == 0) return;
    const std::size_t first = other.first_used_index();
    const std::size_t last = other.last_used_index();
    if (other.counts_length_ == counts_length_) {
        for (std::size_t i = first; i <= last; ++i) counts_[i] += other.counts_[i];
        total_count_ += other.total_count_;
        saturated_ += other.saturated_;
        min_ = std::min(min_, other.min_);
        max_ = std::max(max_, other.max_);
        beyond_max_ = beyond_max_ || other.beyond_max_;
        return;
    }
    // Same sub-bucket structure, different length: index i means the same range in both.
    for (std::size_t i = first; i <= last; ++i) {
        if (other.counts_[i] != 0) record_n(value_at_index(i), other.counts_[i]);
    }
    saturated_ += other.saturated_;
    min_ = std::min(min_, std::min(other.min_, highest_trackable_));
    max_ = std::max(max_, std::min(other.max_, highest_trackable_));
}

std::size_t Histogram::first_used_index() const noexcept {
    if (total_count_ == 0) return 1;
    return beyond_max_ ? 0 : counts_index(min_);
}

std::size_t Histogram::last_used_index() const noexcept {
    if (total_count_ == 0) return 0;
    return beyond_max_ ? counts_length_ - 1 : std::min(counts_index(max_), counts_length_ - 1);
}

void Histogram::add_at_index(std::size_t index, std::uint64_t count) noexcept {
    if (index >= counts_length_ || count == 0) return;
    counts_[index] += count;
    total_count_ += count;
    const std::uint64_t low = value_at_index(index);
    min_ = std::min(min_, low);
    max_ = std::max(max_, std::min(highest_equivalent(low), highest_trackable_));
    if (index > counts_index(max_)) beyond_max_ = true;
}

void Histogram::narrow_extremes(std::uint64_t exact_min, std::uint64_t exact_max) noexcept {
    if (total_count_ == 0) return;
    if (exact_min >= min_ && lowest_equivalent(exact_min) == lowest_equivalent(min_))
        min_ = exact_min;
    if (exact_max <= max_ && lowest_equivalent(exact_max) == lowest_equivalent(max_))
        max_ = exact_max;
}

void Histogram::reset() noexcept {
    const std::size_t first = first_used_index();
    const std::size_t last = last_used_index();
    if (first <= last) std::fill(counts_.get() + first, counts_.get() + last + 1, std::uint64_t{0});
    beyond_max_ = false;
    total_count_ = 0;
    saturated_ = 0;
    min_ = UINT64_MAX;
    max_ = 0;
}

double Histogram::mean() const noexcept {
    if (total_count_ == 0) return 0.0;
    long double sum = 0.0L;
    for (std::size_t i = first_used_index(), last = last_used_index(); i <= last; ++i) {
        if (counts_[i] == 0) continue;
        sum += static_cast<long double>(counts_[i]) *
               static_cast<long double>(median_equivalent(value_at_index(i)));
    }
    return static_cast<double>(sum / static_cast<long double>(total_count_));
}

double Histogram::stddev() const noexcept {
    if (total_count_ == 0) return 0.0;
    const long double mu = mean();
    long double deviation_total = 0.0L;
    for (std::size_t i = first_used_index(), last = last_used_index(); i <= last; ++i) {
        if (counts_[i] == 0) continue;
        const long double dev = static_cast<long double>(median_equivalent(value_at_index(i))) - mu;
        deviation_total += dev * dev * static_cast<long double>(counts_[i]);
    }
    return static_cast<double>(std::sqrt(deviation_total / static_cast<long double>(total_count_)));
}

std::uint64_t Histogram::value_at_percentile(double percentile) const noexcept {
    if (total_count_ == 0) return 0;
    const std::uint64_t rank = rank_for_percentile(percentile, total_count_);
    std::uint64_t cumulative = 0;
    for (std::size_t i = first_used_index(), last = last_used_index(); i <= last; ++i) {
        cumulative += counts_[i];
        if (cumulative >= rank) return within_recorded(highest_equivalent(value_at_index(i)));
    }
    return max_;
}

std::uint64_t Histogram::within_recorded(std::uint64_t value) const noexcept {
    return std::clamp(value, min(), max());
}

PercentileIterator::PercentileIterator(const Histogram& histogram,
                                       std::uint32_t ticks_per_half_distance)
    : histogram_(histogram),
      ticks_per_half_distance_(std::max<std::uint32_t>(1, ticks_per_half_distance)) {}

bool PercentileIterator::next(PercentilePoint& out) noexcept {
    const std::uint64_t total = histogram_.total_count();
    if (total == 0) return false;
    if (started_ && cumulative_ >= total) {
        // Every count has been passed: one final point at exactly 100%.
        if (seen_last_) return false;
        seen_last_ = true;
        out = {last_value_, 100.0, cumulative_};
        return true;
    }
    if (!started_) {
        started_ = true;
        index_ = 0;
        cumulative_ = histogram_.count_at_index(0);
    }
    const std::size_t length = histogram_.counts_length();
    while (index_ < length) {
        const double current =
            100.0 * static_cast<double>(cumulative_) / static_cast<double>(total);
        if (histogram_.count_at_index(index_) != 0 && level_to_iterate_to_ <= current) {
            last_value_ = histogram_.within_recorded(
                Histogram::highest_equivalent(Histogram::value_at_index(index_)));
            out = {last_value_, level_to_iterate_to_, cumulative_};
            // Halve the remaining distance to 100% every ticks_per_half_distance steps.
            const double remaining = 100.0 - level_to_iterate_to_;
            if (remaining <= 0.0) {
                level_to_iterate_to_ = 100.0;
            } else {
                const auto halvings = std::min<std::int64_t>(
                    static_cast<std::int64_t>(std::log(100.0 / remaining) / std::log(2.0)) + 1, 62);
                const double ticks = static_cast<double>(ticks_per_half_distance_) *
                                     std::pow(2.0, static_cast<double>(halvings));
                level_to_iterate_to_ += 100.0 / ticks;
            }
            return true;
        }
        ++index_;
        if (index_ < length) cumulative_ += histogram_.count_at_index(index_);
    }
    return false;
}

std::vector<PercentilePoint> percentile_distribution(const Histogram& histogram,
                                                     std::uint32_t ticks_per_half_distance) {
    std::vector<PercentilePoint> points;
    PercentileIterator it(histogram, ticks_per_half_distance);
    PercentilePoint p;
    while (it.next(p)) points.push_back(p);
    return points;
}

}  // namespace mbstorm::stats
