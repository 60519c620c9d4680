// Per-interval (e.g. 1 s) timeline of throughput, errors and latency percentiles.
//
// Two halves:
//  * IntervalRecorder — owned by one worker thread, no locking. The hot path records into
//    its current histogram; tick() hands the finished interval over when a boundary passes.
//  * IntervalTimeline — shared by all workers. It merges the contributions of one interval
//    from every worker into a pending histogram (a small ring of them) and, once every
//    worker has moved past that interval, reduces it to an IntervalSummary. Summaries live
//    in a vector reserved up front and capped, so memory is bounded however long the run.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include "stats/histogram.hpp"

namespace mbstorm::stats {

struct IntervalSummary {
    std::uint64_t index = 0;            // interval number since the run start
    std::uint64_t start_offset_ns = 0;  // index * interval length
    std::uint64_t duration_ns = 0;      // interval length
    std::uint64_t transactions = 0;     // completed transactions (ok + errors)
    std::uint64_t errors = 0;
    std::uint64_t latency_count = 0;  // latencies recorded (may differ from transactions)
    std::uint64_t p50_ns = 0;
    std::uint64_t p90_ns = 0;
    std::uint64_t p99_ns = 0;
    std::uint64_t p999_ns = 0;
    std::uint64_t max_ns = 0;
    double mean_ns = 0.0;
    // Filled by the engine after the run: the open-loop rate scheduled at the interval's
    // midpoint (0 in closed loop) and the most connections seen open during the interval.
    double target_rate = 0.0;
    std::uint32_t open_connections = 0;

    double transactions_per_second() const noexcept {
        return duration_ns == 0 ? 0.0 : static_cast<double>(transactions) * 1e9 / duration_ns;
    }
};

// Reduces one interval's histogram and counts to a summary.
IntervalSummary summarize_interval(std::uint64_t index, std::uint64_t interval_ns,
                                   const Histogram& latency, std::uint64_t transactions,
                                   std::uint64_t errors) noexcept;

// One interval's full histograms, kept for an interval log (IntervalTimeline::keep_histograms):
// all operations, and one per tag (operation) in the order the recorders number them (none
// when no worker contributed to the interval).
struct IntervalHistograms {
    std::uint64_t index = 0;
    std::uint64_t start_offset_ns = 0;
    std::uint64_t duration_ns = 0;
    Histogram all;
    std::vector<Histogram> by_tag;
};

class IntervalTimeline;

class IntervalRecorder {
  public:
    // interval_ns > 0. Offsets are ns since the run start (the same origin for all workers).
    // tags > 0 keeps one more histogram per tag (operation), for interval logs.
    explicit IntervalRecorder(std::uint64_t interval_ns,
                              std::uint64_t highest_trackable_ns = Histogram::kOneHourNs,
                              std::uint32_t tags = 0);

    // Hot path (forced inline: in the engine's large frame loop GCC left them out of line, a
    // call per answer). Call tick() first whenever time may have crossed a boundary.
    [[gnu::always_inline]] void record_latency(std::uint64_t latency_ns) noexcept {
        histogram_.record(latency_ns);
    }
    // The same, also counted under tag when the recorder keeps tags (ignored otherwise).
    [[gnu::always_inline]] void record_latency(std::uint64_t latency_ns,
                                               std::uint32_t tag) noexcept {
        histogram_.record(latency_ns);
        if (tag < tagged_.size()) tagged_[tag].record(latency_ns);
    }
    [[gnu::always_inline]] void record_transaction(bool error) noexcept {
        ++transactions_;
        errors_ += error ? 1 : 0;
    }

    // Every interval's all-operations histogram is also added into `total` when the interval
    // ends (roll-over, flush), so a caller that keeps a run-long histogram of the same
    // latencies records each once, here, instead of twice. nullptr: no such total.
    void fold_into(Histogram* total) noexcept { total_ = total; }
    // Several tags, each with a run-long histogram of its own (totals[tag], from a recorder
    // built with tags >= totals.size()): record_tagged() records a latency once, into its
    // tag's interval histogram, and at each interval end the tags' histograms are summed into
    // the all-tags one and each is added into its total. Call before recording; then record
    // through record_tagged() only (record_latency() would count a latency twice).
    void fold_tags_into(std::vector<Histogram*> totals) { tag_totals_ = std::move(totals); }
    [[gnu::always_inline]] void record_tagged(std::uint64_t latency_ns,
                                              std::uint32_t tag) noexcept {
        tagged_[tag].record(latency_ns);
    }

    // Cheap when no boundary passed (one compare). Otherwise contributes the current
    // interval to timeline as worker `contributor` and starts the interval holding now.
    void tick(std::uint64_t now_offset_ns, IntervalTimeline& timeline,
              std::uint32_t contributor) noexcept {
        if (now_offset_ns >= next_boundary_ns_) roll_over(now_offset_ns, timeline, contributor);
    }
    // End of run: contributes whatever is in the current interval.
    void flush(IntervalTimeline& timeline, std::uint32_t contributor) noexcept;

    std::uint64_t current_index() const noexcept { return current_index_; }
    const Histogram& histogram() const noexcept { return histogram_; }
    std::uint64_t transactions() const noexcept { return transactions_; }
    std::uint64_t errors() const noexcept { return errors_; }
    void clear() noexcept;

  private:
    void roll_over(std::uint64_t now_offset_ns, IntervalTimeline& timeline,
                   std::uint32_t contributor) noexcept;
    void fold() noexcept;  // the interval's histograms into the totals, at its end

    std::uint64_t interval_ns_;
    std::uint64_t current_index_ = 0;
    std::uint64_t next_boundary_ns_;
    Histogram histogram_;
    std::vector<Histogram> tagged_;
    Histogram* total_ = nullptr;          // fold_into()
    std::vector<Histogram*> tag_totals_;  // fold_tags_into()
    std::uint64_t transactions_ = 0;
    std::uint64_t errors_ = 0;
};

class IntervalTimeline {
  public:
    // contributors: number of IntervalRecorders (worker threads) feeding this timeline.
    // max_intervals: cap on stored summaries (reserve run_duration / interval + a few);
    // intervals beyond it are counted in dropped_intervals().
    IntervalTimeline(std::uint64_t interval_ns, std::uint32_t contributors,
                     std::size_t max_intervals,
                     std::uint64_t highest_trackable_ns = Histogram::kOneHourNs);

    // Before any contribution: keep every interval's histograms (all operations and one per
    // tag) for drain_histograms(). Recorders should then be built with tags().
    void keep_histograms(std::uint32_t tags);
    std::uint32_t tags() const noexcept { return tags_; }

    // Thread-safe. Merges one interval of one worker; the worker is then done with every
    // interval <= index. A contribution for an already summarized interval only adds its
    // counts (counted in late_contributions()); its latencies reach no summary or log.
    void contribute(std::uint32_t contributor, std::uint64_t index, const Histogram& latency,
                    std::uint64_t transactions, std::uint64_t errors) noexcept {
        contribute(contributor, index, latency, {}, transactions, errors);
    }
    // tagged: the worker's per-tag histograms (fewer than tags() is fine).
    void contribute(std::uint32_t contributor, std::uint64_t index, const Histogram& latency,
                    std::span<const Histogram> tagged, std::uint64_t transactions,
                    std::uint64_t errors) noexcept;
    // Hands every interval summarized since the last call to `use`, oldest first, outside the
    // lock (call from one thread). Allocation-free in steady state: the histograms go back to
    // a pool. Only with keep_histograms().
    void drain_histograms(const std::function<void(const IntervalHistograms&)>& use);
    // Summarizes every pending interval (call after all workers flushed).
    void finish() noexcept;

    // Most recent summarized interval (for the live progress line).
    std::optional<IntervalSummary> latest() const;
    std::vector<IntervalSummary> summaries() const;
    // The summaries from position `from` on, into `out` (cleared first; reserve it to keep
    // this allocation-free).
    void copy_summaries(std::size_t from, std::vector<IntervalSummary>& out) const;
    std::uint64_t interval_ns() const noexcept { return interval_ns_; }
    std::uint64_t dropped_intervals() const;
    // Sets of per-tag histograms made so far (keep_histograms()): each is tags() histograms;
    // only intervals in flight or waiting for the drain hold one.
    std::size_t tag_sets_made() const;
    std::uint64_t late_contributions() const;

  private:
    static constexpr std::size_t kPendingSlots = 4;
    struct Pending {
        Histogram latency;
        std::uint64_t transactions = 0;
        std::uint64_t errors = 0;
        std::vector<Histogram> by_tag;  // keep_histograms(): from its first contribution
    };
    void summarize_next() noexcept;                            // requires mutex_ held
    void keep_completed(Pending& slot) noexcept;               // requires mutex_ held
    void take_tag_set(std::vector<Histogram>& into) noexcept;  // requires mutex_ held

    mutable std::mutex mutex_;
    std::uint64_t interval_ns_;
    std::size_t max_intervals_;
    std::vector<std::uint64_t> done_before_;  // per contributor: all intervals < this are in
    std::vector<Pending> pending_;            // ring indexed by interval % kPendingSlots
    std::uint64_t next_to_summarize_ = 0;
    std::vector<IntervalSummary> summaries_;
    std::uint64_t dropped_ = 0;
    std::uint64_t late_ = 0;
    std::uint64_t highest_trackable_ns_;
    // keep_histograms(): finished intervals wait in completed_ for drain_histograms(); their
    // storage comes from and returns to spare_.
    std::uint32_t tags_ = 0;
    bool keep_ = false;
    std::vector<std::unique_ptr<IntervalHistograms>> completed_;
    std::vector<std::unique_ptr<IntervalHistograms>> spare_;
    std::vector<std::unique_ptr<IntervalHistograms>> draining_;  // drain_histograms() only
    std::vector<std::vector<Histogram>> spare_tag_sets_;         // by_tag sets between intervals
    std::size_t tag_sets_made_ = 0;
};

}  // namespace mbstorm::stats
