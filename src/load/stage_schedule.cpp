#include "load/stage_schedule.hpp"

#include <algorithm>
#include <cmath>

namespace mbstorm::load {

StageSchedule::StageSchedule(const Plan& plan)
    : initial_rate_(plan.model == LoadModel::OpenLoop ? plan.rate : 0),
      initial_connections_(plan.connections),
      peak_connections_(plan.connections),
      peak_rate_(initial_rate_) {
    double rate = initial_rate_;
    double connections = plan.connections;
    std::int64_t start = 0;
    spans_.reserve(plan.stages.size());
    for (const Stage& stage : plan.stages) {
        Span span;
        span.start_ns = start;
        span.end_ns = start + stage.duration.count();
        span.to_rate = plan.model == LoadModel::OpenLoop ? stage.target_rate.value_or(rate) : 0;
        span.to_connections = stage.target_connections ? *stage.target_connections : connections;
        // A constant stage jumps to its values at its start.
        span.from_rate = stage.ramp == Ramp::Linear ? rate : span.to_rate;
        span.from_connections = stage.ramp == Ramp::Linear ? connections : span.to_connections;
        rate = span.to_rate;
        connections = span.to_connections;
        start = span.end_ns;
        peak_rate_ = std::max({peak_rate_, span.from_rate, span.to_rate});
        peak_connections_ = std::max(peak_connections_, static_cast<std::uint32_t>(connections));
        spans_.push_back(span);
    }
    total_ns_ = start;
}

std::size_t StageSchedule::stage_at(std::int64_t offset_ns) const noexcept {
    if (spans_.empty() || offset_ns <= 0) return 0;
    // Few stages, and the engine asks with rising times: a linear search is plenty.
    for (std::size_t i = 0; i < spans_.size(); ++i) {
        if (offset_ns < spans_[i].end_ns) return i;
    }
    return spans_.size() - 1;
}

std::int64_t StageSchedule::next_boundary_ns(std::int64_t offset_ns) const noexcept {
    if (!spans_.empty() && offset_ns < 0) return 0;
    for (const Span& s : spans_) {
        if (offset_ns < s.end_ns) return s.end_ns;
    }
    return INT64_MAX;
}

StageTargets StageSchedule::stage_from(std::size_t stage) const noexcept {
    const Span& s = spans_[stage];
    return {stage, s.from_rate, static_cast<std::uint32_t>(std::llround(s.from_connections))};
}

StageTargets StageSchedule::stage_to(std::size_t stage) const noexcept {
    const Span& s = spans_[stage];
    return {stage, s.to_rate, static_cast<std::uint32_t>(std::llround(s.to_connections))};
}

double StageSchedule::scheduled_transactions(std::int64_t offset_ns) const noexcept {
    if (offset_ns <= 0) return 0.0;
    if (spans_.empty()) return initial_rate_ * static_cast<double>(offset_ns) / 1e9;
    double total = 0.0;
    for (const Span& s : spans_) {
        if (offset_ns <= s.start_ns) break;
        const std::int64_t length = s.end_ns - s.start_ns;
        const std::int64_t covered = std::min(offset_ns, s.end_ns) - s.start_ns;
        if (length <= 0 || covered <= 0) continue;
        // Linear in time: the mean of the rates at both ends of the covered part.
        const double progress = static_cast<double>(covered) / static_cast<double>(length);
        const double rate_end = s.from_rate + (s.to_rate - s.from_rate) * progress;
        total += (s.from_rate + rate_end) / 2.0 * static_cast<double>(covered) / 1e9;
    }
    // Past the last stage the final rate holds.
    if (offset_ns > total_ns_)
        total += spans_.back().to_rate * static_cast<double>(offset_ns - total_ns_) / 1e9;
    return total;
}

StageTargets StageSchedule::at(std::int64_t offset_ns) const noexcept {
    if (spans_.empty()) return {0, initial_rate_, initial_connections_};
    const std::size_t i = stage_at(offset_ns);
    const Span& s = spans_[i];
    const std::int64_t length = s.end_ns - s.start_ns;
    const double progress =
        length <= 0
            ? 1.0
            : std::clamp(static_cast<double>(offset_ns - s.start_ns) / static_cast<double>(length),
                         0.0, 1.0);
    StageTargets t;
    t.stage = i;
    t.rate = s.from_rate + (s.to_rate - s.from_rate) * progress;
    t.connections = static_cast<std::uint32_t>(
        std::llround(s.from_connections + (s.to_connections - s.from_connections) * progress));
    return t;
}

}  // namespace mbstorm::load
