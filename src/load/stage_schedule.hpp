// The staged schedule of a run (Plan::stages) as a pure function of time: the open-loop rate
// and the connection count the engine should hold at any moment, and which stage a moment
// belongs to. A linear stage ramps from the previous stage's end values (the first stage from
// the plan's top-level rate and connections) to its own; a constant stage holds its values.
// A stage that leaves a value unset keeps the previous one.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "load/plan.hpp"

namespace mbstorm::load {

struct StageTargets {
    std::size_t stage = 0;
    double rate = 0;                // open loop: transactions/s over all threads
    std::uint32_t connections = 0;  // over all threads
};

class StageSchedule {
  public:
    explicit StageSchedule(const Plan& plan);

    bool empty() const noexcept { return spans_.empty(); }
    std::size_t stages() const noexcept { return spans_.size(); }
    // Sum of the stage durations (0 without stages).
    std::int64_t total_ns() const noexcept { return total_ns_; }
    std::int64_t stage_start_ns(std::size_t stage) const noexcept { return spans_[stage].start_ns; }
    std::int64_t stage_end_ns(std::size_t stage) const noexcept { return spans_[stage].end_ns; }

    // Targets `offset_ns` after the stages began (the end of warm-up). Before the start: the
    // start values of the first stage (warm-up runs at them); past the end: the final values.
    StageTargets at(std::int64_t offset_ns) const noexcept;
    // The first stage boundary (start or end of a stage) after `offset_ns`; INT64_MAX past the
    // end.
    std::int64_t next_boundary_ns(std::int64_t offset_ns) const noexcept;
    // The stage `offset_ns` falls in (clamped to the first and last stage).
    std::size_t stage_at(std::int64_t offset_ns) const noexcept;

    // What a stage asks for at its start and at its end (equal unless it ramps).
    StageTargets stage_from(std::size_t stage) const noexcept;
    StageTargets stage_to(std::size_t stage) const noexcept;
    // Transactions the open-loop schedule asks for in [0, offset_ns) (0 in a closed loop):
    // the integral of the rate.
    double scheduled_transactions(std::int64_t offset_ns) const noexcept;

    std::uint32_t peak_connections() const noexcept { return peak_connections_; }
    double peak_rate() const noexcept { return peak_rate_; }

  private:
    struct Span {
        std::int64_t start_ns = 0, end_ns = 0;
        double from_rate = 0, to_rate = 0;
        double from_connections = 0, to_connections = 0;
    };
    std::vector<Span> spans_;
    std::int64_t total_ns_ = 0;
    double initial_rate_ = 0;
    std::uint32_t initial_connections_ = 0;
    std::uint32_t peak_connections_ = 0;
    double peak_rate_ = 0;
};

}  // namespace mbstorm::load
