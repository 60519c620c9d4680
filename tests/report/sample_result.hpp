// Deterministic synthetic RunResult for report tests and tests/tools/write_sample_report.
#pragma once

#include <cmath>
#include <random>

#include "stats/run_result.hpp"

namespace mbstorm::report::testing {

// Three stages (warm, steady, spike) over `seconds`, two operations, a few error classes.
inline stats::RunResult make_sample_result(std::uint64_t seconds = 30, bool with_stages = true) {
    constexpr std::uint64_t kS = 1'000'000'000;
    stats::RunResult r;
    auto& m = r.metadata;
    m.tool_version = "mbstorm 0.1.0";
    m.target = "127.0.0.1:15020";
    m.threads = 2;
    m.connections = 16;
    m.depth = 4;
    m.model = stats::LoadModel::Open;
    m.rate_per_second = 2000;
    m.requested_duration_ns = seconds * kS;
    m.measured_duration_ns = seconds * kS;
    m.warmup_ns = 2 * kS;
    m.start_time = std::chrono::system_clock::time_point(std::chrono::seconds(1714564800));
    m.notes = {"embedded slave on 127.0.0.1:15020", "synthetic data <for tests> & demos"};

    r.operations.push_back({"read_holding_registers", 0x03, stats::Histogram(), {}});
    r.operations.push_back({"write_single_register", 0x06, stats::Histogram(), {}});

    const std::uint64_t stage_len = seconds / 3;
    if (with_stages) {
        const char* names[] = {"warm", "steady", "spike"};
        for (std::uint32_t i = 0; i < 3; ++i) {
            stats::StageResult st;
            st.name = names[i];
            st.index = i + 1;
            st.start_offset_ns = i * stage_len * kS;
            st.end_offset_ns = (i == 2 ? seconds : (i + 1) * stage_len) * kS;
            // The first stage ramps the rate up from 500/s; the others hold 2,000/s.
            st.rate_from = i == 0 ? 500.0 : 2000.0;
            st.rate_to = 2000.0;
            st.connections_from = st.connections_to = 16;
            r.stages.push_back(std::move(st));
        }
    }

    std::mt19937_64 rng(42);
    std::lognormal_distribution<double> base(std::log(180e3), 0.35);  // ~180 µs
    std::exponential_distribution<double> tail(1.0 / 4e6);            // ms-scale tail
    stats::IntervalTimeline timeline(kS, 1, seconds + 1);
    stats::IntervalRecorder recorder(kS);
    constexpr std::uint64_t kPerSecond = 2000;
    for (std::uint64_t i = 0; i < seconds * kPerSecond; ++i) {
        const std::uint64_t now = i * (kS / kPerSecond);
        const std::uint64_t second = now / kS;
        const bool spike = second >= 2 * stage_len;
        recorder.tick(now, timeline, 0);
        auto& op = r.operations[i % 5 == 0 ? 1 : 0];
        stats::StageResult* stage = nullptr;
        if (with_stages) stage = &r.stages[std::min<std::uint64_t>(second / stage_len, 2)];
        // Throughput ramps in the first stage.
        if (second < stage_len && (i % kPerSecond) > kPerSecond * (second + 1) / stage_len)
            continue;
        double latency = base(rng);
        if (i % 97 == 0) latency += tail(rng);
        if (spike) latency *= 3.0;
        const auto ns = static_cast<std::uint64_t>(latency);

        stats::Outcome outcome = stats::Outcome::Ok;
        std::uint8_t exception = 0;
        if (i % 1009 == 0)
            outcome = stats::Outcome::Timeout;
        else if (i % 733 == 0) {
            outcome = stats::Outcome::Exception;
            exception = 0x02;
        } else if (spike && i % 211 == 0) {
            outcome = stats::Outcome::Exception;
            exception = 0x06;
        } else if (i % 4999 == 0)
            outcome = stats::Outcome::WrongUnitId;

        for (stats::OutcomeCounters* c : {&r.counters, &op.counters}) {
            c->transactions_sent += 1;
            c->bytes_sent += 12;
            c->bytes_received += outcome == stats::Outcome::Timeout ? 0 : 13;
            if (outcome == stats::Outcome::Exception)
                c->record_exception(exception);
            else
                c->record(outcome);
        }
        if (stage != nullptr) {
            stage->counters.transactions_sent += 1;
            if (outcome == stats::Outcome::Exception)
                stage->counters.record_exception(exception);
            else
                stage->counters.record(outcome);
        }
        recorder.record_transaction(outcome != stats::Outcome::Ok);
        if (outcome == stats::Outcome::Timeout) continue;  // no latency for timeouts
        r.latency.record(ns);
        op.latency.record(ns);
        if (stage != nullptr) stage->latency.record(ns);
        recorder.record_latency(ns);
    }
    recorder.flush(timeline, 0);
    timeline.finish();
    r.timeline = timeline.summaries();
    for (auto& iv : r.timeline) {  // the offered rate ramps with the first stage, as above
        const std::uint64_t second = iv.start_offset_ns / kS;
        iv.target_rate = second < stage_len ? kPerSecond * (second + 1.0) / stage_len : kPerSecond;
        iv.open_connections = 16;
    }
    r.timeline_interval_ns = kS;
    r.schedule_lag.engine = {37, 2'400'000, 37 * 600'000};
    r.connections.opened = 16;
    r.connections.reconnects = 1;
    r.connections.closed_by_peer = 1;
    r.connections.peak_open = 16;
    r.thresholds.push_back({"p99 < 5ms", 3.1e6, "3.10ms", true});
    r.thresholds.push_back({"error_rate < 0.1%", 0.0021, "0.21%", false});
    return r;
}

}  // namespace mbstorm::report::testing
