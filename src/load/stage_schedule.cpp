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
