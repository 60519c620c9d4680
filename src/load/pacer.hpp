// Open-loop schedule of one thread: the intended send time of every transaction at the
// thread's share of the total rate, evenly spaced or as a Poisson process. Latency is measured
// from the intended time (as wrk2 does), so a stalled target or a slow engine cannot hide its
// queueing delay (coordinated omission). LagTracker counts the sends that left late.
#pragma once

#include <algorithm>
#include <cstdint>

#include "load/plan.hpp"
#include "load/rng.hpp"
#include "stats/run_result.hpp"

namespace mbstorm::load {

class Pacer {
  public:
    Pacer() = default;
    // rate: transactions per second for this thread (<= 0: paused). The first send is due at
    // `start_ns`.
    Pacer(double rate, Arrival arrival, std::uint64_t seed, std::int64_t start_ns) noexcept;

    // Intended send time of the next transaction.
    std::int64_t next_intended_ns() const noexcept { return next_ns_; }
    // True when the next transaction is due at `now_ns`.
    bool due(std::int64_t now_ns) const noexcept { return next_ns_ <= now_ns; }
    // Consumes the next transaction and schedules the one after it.
    void advance() noexcept;
    std::uint64_t scheduled() const noexcept { return count_; }

    // Changes the rate from `now_ns` on (stages). The next send keeps its slot unless the new
    // rate brings it closer (a send already overdue stays overdue: no backlog is forgiven).
    // A rate <= 0 pauses the schedule until a positive rate is set.
    void set_rate(double rate, std::int64_t now_ns) noexcept;
    bool paused() const noexcept { return rate_ <= 0; }
    double rate() const noexcept { return rate_; }

  private:
    std::int64_t gap_ns() noexcept;  // one (even or exponential) gap at the current rate

    double rate_ = 1;
    double period_ns_ = 1e9;
    Arrival arrival_ = Arrival::Even;
    Rng rng_;
    std::int64_t origin_ns_ = 0;  // even: time of transaction 0 of the current rate
    std::uint64_t count_ = 0;     // transactions consumed in total
    std::uint64_t since_origin_ = 0;
    std::int64_t next_ns_ = 0;
};

// Counts late sends by cause. A send is blamed on the target when, since the last send that
// left on time, the schedule was found due with no connection able to take it (every in-flight
// window full, or none open), and it left later than the engine itself had fallen behind;
// otherwise on the engine. (An engine that stalled sends its backlog at once when it wakes: a
// backlog longer than the windows fills them with requests the target has only just been
// given, and the sends still due wait for those. They are as late as the engine made them,
// not the target: only a send later than every one of the engine's own late sends waited for
// a target that was slow to answer.)
class LagTracker {
  public:
    explicit LagTracker(std::int64_t threshold_ns = 1'000'000) noexcept
        : threshold_(threshold_ns) {}
    // A send was due but no connection had room for it.
    void note_window_full() noexcept { waiting_for_target_ = true; }
    // measured: false during warm-up (the cause is still tracked, nothing is counted).
    void record(std::int64_t intended_ns, std::int64_t actual_ns, bool measured = true) noexcept {
        const std::int64_t lag = actual_ns - intended_ns;
        if (lag <= threshold_) {
            waiting_for_target_ = false;
            engine_behind_ns_ = 0;
            return;
        }
        const bool target = waiting_for_target_ && lag > engine_behind_ns_ + threshold_;
        if (!target) engine_behind_ns_ = std::max(engine_behind_ns_, lag);
        if (!measured) return;
        stats::LagCounts& into = target ? lag_.target : lag_.engine;
        ++into.late_sends;
        into.total_lag_ns += static_cast<std::uint64_t>(lag);
        if (static_cast<std::uint64_t>(lag) > into.max_lag_ns)
            into.max_lag_ns = static_cast<std::uint64_t>(lag);
    }
    const stats::ScheduleLag& lag() const noexcept { return lag_; }
    std::uint64_t late_sends() const noexcept { return lag_.total().late_sends; }
    std::uint64_t max_lag_ns() const noexcept { return lag_.total().max_lag_ns; }
    std::uint64_t total_lag_ns() const noexcept { return lag_.total().total_lag_ns; }

  private:
    std::int64_t threshold_;
    bool waiting_for_target_ = false;
    // The largest lag of the engine's own late sends since the last send on time.
    std::int64_t engine_behind_ns_ = 0;
    stats::ScheduleLag lag_;
};

}  // namespace mbstorm::load
