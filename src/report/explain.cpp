#include "report/explain.hpp"

#include <fmt/format.h>

#include "report/units.hpp"

namespace mbstorm::report {

std::vector<double> rate_schedule(const stats::RunResult& r) {
    std::vector<double> rates;
    if (r.metadata.model != stats::LoadModel::Open) return rates;
    auto push = [&rates](double rate) {
        if (rates.empty() || rates.back() != rate) rates.push_back(rate);
    };
    if (r.stages.empty()) {
        push(r.metadata.rate_per_second);
        return rates;
    }
    for (const auto& st : r.stages) {
        push(st.rate_from);
        push(st.rate_to);
    }
    return rates;
}

std::string load_model_text(const stats::RunResult& r) {
    if (r.metadata.model != stats::LoadModel::Open) return "closed loop";
    const std::vector<double> rates = rate_schedule(r);
    std::string steps;
    for (const double rate : rates) {
        if (!steps.empty()) steps += " → ";
        steps += format_rate(rate);
    }
    return fmt::format("open loop, {}{} req/s", r.stages.empty() ? "" : "stages ", steps);
}

std::string stage_rate_text(const stats::StageResult& stage, stats::LoadModel model) {
    if (model != stats::LoadModel::Open) return "-";
    if (stage.rate_from == stage.rate_to) return format_rate(stage.rate_to);
    return fmt::format("{} → {}", format_rate(stage.rate_from), format_rate(stage.rate_to));
}

const char* schedule_lag_cause(const stats::ScheduleLag& lag) {
    const bool engine = lag.engine.late_sends != 0;
    const bool target = lag.target.late_sends != 0;
    if (engine && target) return "engine_and_target";
    if (engine) return "engine";
    if (target) return "target";
    return "none";
}

std::vector<std::string> schedule_lines(const stats::RunResult& r) {
    std::vector<std::string> lines;
    if (r.metadata.model != stats::LoadModel::Open) return lines;
    const auto& lag = r.schedule_lag;
    if (lag.target.late_sends != 0) {
        lines.push_back(fmt::format(
            "target not keeping up: {} late sends waited for answers (in-flight window full: {} "
            "connection{} x depth {}), max lag {}, mean lag {}; to reach the rate, widen the "
            "window (--connections, --depth) if the target serves more at once, else lower "
            "--rate to what it sustained ({} tx/s)",
            format_count(lag.target.late_sends), format_count(r.metadata.connections),
            r.metadata.connections == 1 ? "" : "s", r.metadata.depth,
            format_latency(lag.target.max_lag_ns), format_latency(lag.target.mean_lag_ns()),
            format_rate(r.throughput())));
    }
    if (lag.engine.late_sends != 0) {
        lines.push_back(fmt::format(
            "engine fell behind: {} late sends (mbstorm's own CPU or scheduling), max lag {}, "
            "mean lag {}",
            format_count(lag.engine.late_sends), format_latency(lag.engine.max_lag_ns),
            format_latency(lag.engine.mean_lag_ns())));
    }
    if (lines.empty()) lines.emplace_back("kept (no late sends)");
    return lines;
}

std::vector<std::string> hint_lines(const stats::RunResult& r) {
    std::vector<std::string> hints;
    const std::uint32_t depth = r.metadata.depth;
    if (depth <= 1) return hints;
    const std::uint64_t skipped = r.pipelining.skipped_requests;
    const std::uint64_t timeouts = r.counters.count(stats::Outcome::Timeout);
    if (skipped != 0) {
        hints.push_back(fmt::format(
            "{} request{} timed out while later ones on the same connection were answered: the "
            "target skipped them, as one that answers one request at a time (no pipelining) "
            "does; use --depth 1 (depth: 1 in a scenario)",
            format_count(skipped), skipped == 1 ? "" : "s"));
    } else if (timeouts != 0) {
        hints.push_back(fmt::format(
            "{} timeout{} at depth {}: a target that answers one request at a time loses the "
            "requests queued behind the first; if yours is one, use --depth 1 (depth: 1 in a "
            "scenario)",
            format_count(timeouts), timeouts == 1 ? "" : "s", depth));
    }
    return hints;
}

}  // namespace mbstorm::report
