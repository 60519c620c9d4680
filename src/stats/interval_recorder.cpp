#include "stats/interval_recorder.hpp"

#include <algorithm>

namespace mbstorm::stats {

IntervalSummary summarize_interval(std::uint64_t index, std::uint64_t interval_ns,
                                   const Histogram& latency, std::uint64_t transactions,
                                   std::uint64_t errors) noexcept {
    IntervalSummary s;
    s.index = index;
    s.start_offset_ns = index * interval_ns;
    s.duration_ns = interval_ns;
    s.transactions = transactions;
    s.errors = errors;
    s.latency_count = latency.total_count();
    if (!latency.empty()) {
        s.p50_ns = latency.value_at_percentile(50.0);
        s.p90_ns = latency.value_at_percentile(90.0);
        s.p99_ns = latency.value_at_percentile(99.0);
        s.p999_ns = latency.value_at_percentile(99.9);
        s.max_ns = latency.max();
        s.mean_ns = latency.mean();
    }
    return s;
}

IntervalRecorder::IntervalRecorder(std::uint64_t interval_ns, std::uint64_t highest_trackable_ns,
                                   std::uint32_t tags)
    : interval_ns_(std::max<std::uint64_t>(1, interval_ns)),
      next_boundary_ns_(interval_ns_),
      histogram_(highest_trackable_ns),
      tagged_(tags, Histogram(highest_trackable_ns)) {}

void IntervalRecorder::roll_over(std::uint64_t now_offset_ns, IntervalTimeline& timeline,
                                 std::uint32_t contributor) noexcept {
    fold();
    timeline.contribute(contributor, current_index_, histogram_, tagged_, transactions_, errors_);
    clear();
    current_index_ = now_offset_ns / interval_ns_;
    next_boundary_ns_ = (current_index_ + 1) * interval_ns_;
}

void IntervalRecorder::flush(IntervalTimeline& timeline, std::uint32_t contributor) noexcept {
    fold();
    timeline.contribute(contributor, current_index_, histogram_, tagged_, transactions_, errors_);
    clear();
}

void IntervalRecorder::fold() noexcept {
    for (std::size_t tag = 0; tag < tag_totals_.size() && tag < tagged_.size(); ++tag) {
        histogram_.add(tagged_[tag]);
        if (tag_totals_[tag] != nullptr) tag_totals_[tag]->add(tagged_[tag]);
    }
    if (total_ != nullptr) total_->add(histogram_);
}

void IntervalRecorder::clear() noexcept {
    histogram_.reset();
    for (auto& h : tagged_) h.reset();
    transactions_ = 0;
    errors_ = 0;
}

IntervalTimeline::IntervalTimeline(std::uint64_t interval_ns, std::uint32_t contributors,
                                   std::size_t max_intervals, std::uint64_t highest_trackable_ns)
    : interval_ns_(std::max<std::uint64_t>(1, interval_ns)),
      max_intervals_(max_intervals),
      done_before_(std::max<std::uint32_t>(1, contributors), 0),
      highest_trackable_ns_(highest_trackable_ns) {
    pending_.reserve(kPendingSlots);
    for (std::size_t i = 0; i < kPendingSlots; ++i) {
        pending_.push_back(Pending{Histogram(highest_trackable_ns), 0, 0, {}});
    }
    summaries_.reserve(max_intervals_);
}

void IntervalTimeline::keep_histograms(std::uint32_t tags) {
    std::lock_guard lock(mutex_);
    keep_ = true;
    tags_ = tags;
    // A few sets in reserve: the drain empties the queue every few milliseconds, so more are
    // made only when it falls behind. The per-tag histograms (one per operation: 270 MB a set
    // for 1,000 operations) are taken by an interval when its first contribution comes and
    // given back by the drain, so that only intervals in flight hold them (issue #31: with
    // them in every pending slot and every spare set a 1,000-operation run took 2.96 GB).
    constexpr std::size_t kSpareSets = 4;
    constexpr std::size_t kSpareTagSets = 2;
    constexpr std::size_t kQueueCapacity = 64;
    completed_.reserve(kQueueCapacity);
    spare_.reserve(kQueueCapacity);
    draining_.reserve(kQueueCapacity);
    spare_tag_sets_.reserve(kQueueCapacity);
    for (std::size_t i = 0; i < kSpareSets; ++i) {
        auto set = std::make_unique<IntervalHistograms>();
        set->all = Histogram(highest_trackable_ns_);
        spare_.push_back(std::move(set));
    }
    for (std::size_t i = 0; i < kSpareTagSets && tags > 0; ++i) {
        spare_tag_sets_.emplace_back(tags, Histogram(highest_trackable_ns_));
        ++tag_sets_made_;
    }
}

void IntervalTimeline::take_tag_set(std::vector<Histogram>& into) noexcept {
    if (!spare_tag_sets_.empty()) {
        into = std::move(spare_tag_sets_.back());
        spare_tag_sets_.pop_back();
        return;
    }
    try {
        into.assign(tags_, Histogram(highest_trackable_ns_));
        ++tag_sets_made_;
    } catch (...) {
        into.clear();  // out of memory: the log misses this interval's tags
    }
}

void IntervalTimeline::keep_completed(Pending& slot) noexcept {
    std::unique_ptr<IntervalHistograms> set;
    if (!spare_.empty()) {
        set = std::move(spare_.back());
        spare_.pop_back();
    } else {
        try {
            set = std::make_unique<IntervalHistograms>();
            set->all = Histogram(highest_trackable_ns_);
            completed_.reserve(completed_.size() + 1);
        } catch (...) {
            return;  // out of memory: the log misses this interval, the summary has it
        }
    }
    set->index = next_to_summarize_;
    set->start_offset_ns = next_to_summarize_ * interval_ns_;
    set->duration_ns = interval_ns_;
    // Swaps, not copies: the slot takes the set's cleared histogram and gives its tags' away
    // (none when no contribution came).
    std::swap(set->all, slot.latency);
    std::swap(set->by_tag, slot.by_tag);
    completed_.push_back(std::move(set));
}

void IntervalTimeline::drain_histograms(const std::function<void(const IntervalHistograms&)>& use) {
    {
        std::lock_guard lock(mutex_);
        if (completed_.empty()) return;
        std::swap(draining_, completed_);
    }
    for (const auto& set : draining_) use(*set);
    for (auto& set : draining_) {
        set->all.reset();
        for (auto& h : set->by_tag) h.reset();
    }
    std::lock_guard lock(mutex_);
    for (auto& set : draining_) {
        if (!set->by_tag.empty()) spare_tag_sets_.push_back(std::move(set->by_tag));
        set->by_tag.clear();
        spare_.push_back(std::move(set));
    }
    draining_.clear();
}

void IntervalTimeline::summarize_next() noexcept {
    Pending& slot = pending_[next_to_summarize_ % kPendingSlots];
    if (summaries_.size() < max_intervals_) {
        summaries_.push_back(summarize_interval(next_to_summarize_, interval_ns_, slot.latency,
                                                slot.transactions, slot.errors));
    } else {
        ++dropped_;
    }
    if (keep_) keep_completed(slot);
    slot.latency.reset();
    for (auto& h : slot.by_tag) h.reset();
    slot.transactions = 0;
    slot.errors = 0;
    ++next_to_summarize_;
}

void IntervalTimeline::contribute(std::uint32_t contributor, std::uint64_t index,
                                  const Histogram& latency, std::span<const Histogram> tagged,
                                  std::uint64_t transactions, std::uint64_t errors) noexcept {
    std::lock_guard lock(mutex_);
    if (index < next_to_summarize_) {
        // Already summarized (this worker lagged behind the pending window): keep the
        // counts exact; its latencies can no longer change that interval's percentiles.
        ++late_;
        if (index < summaries_.size()) {
            summaries_[index].transactions += transactions;
            summaries_[index].errors += errors;
        }
    } else {
        while (index >= next_to_summarize_ + kPendingSlots) summarize_next();
        Pending& slot = pending_[index % kPendingSlots];
        if (keep_ && !tagged.empty() && slot.by_tag.empty()) take_tag_set(slot.by_tag);
        slot.latency.add(latency);
        for (std::size_t t = 0; t < tagged.size() && t < slot.by_tag.size(); ++t)
            slot.by_tag[t].add(tagged[t]);
        slot.transactions += transactions;
        slot.errors += errors;
    }
    if (contributor < done_before_.size()) {
        done_before_[contributor] = std::max(done_before_[contributor], index + 1);
    }
    const std::uint64_t all_done = *std::min_element(done_before_.begin(), done_before_.end());
    while (next_to_summarize_ < all_done) summarize_next();
}

void IntervalTimeline::finish() noexcept {
    std::lock_guard lock(mutex_);
    std::uint64_t end = next_to_summarize_;
    for (auto done : done_before_) end = std::max(end, done);
    while (next_to_summarize_ < end) summarize_next();
}

std::optional<IntervalSummary> IntervalTimeline::latest() const {
    std::lock_guard lock(mutex_);
    if (summaries_.empty()) return std::nullopt;
    return summaries_.back();
}

std::vector<IntervalSummary> IntervalTimeline::summaries() const {
    std::lock_guard lock(mutex_);
    return summaries_;
}

void IntervalTimeline::copy_summaries(std::size_t from, std::vector<IntervalSummary>& out) const {
    out.clear();
    std::lock_guard lock(mutex_);
    for (std::size_t i = from; i < summaries_.size(); ++i) out.push_back(summaries_[i]);
}

std::uint64_t IntervalTimeline::dropped_intervals() const {
    std::lock_guard lock(mutex_);
    return dropped_;
}

std::size_t IntervalTimeline::tag_sets_made() const {
    std::lock_guard lock(mutex_);
    return tag_sets_made_;
}

std::uint64_t IntervalTimeline::late_contributions() const {
    std::lock_guard lock(mutex_);
    return late_;
}

}  // namespace mbstorm::stats
