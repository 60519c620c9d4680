// Everything a finished run hands to the reports (console, JSON, .hgrm, HTML).
// Filled by the load engine (and later the scenario layer); read-only for report/.
// All durations and offsets are nanoseconds; offsets are measured from the run start
// (the end of warm-up: warm-up samples are not in any histogram).
#pragma once

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "stats/counters.hpp"
#include "stats/histogram.hpp"
#include "stats/interval_recorder.hpp"

namespace mbstorm::stats {

enum class LoadModel : std::uint8_t {
    Closed,  // each connection keeps `depth` requests in flight, sends as answers arrive
    Open,    // requests are sent on a fixed schedule (`rate_per_second`) whatever the latency
};
constexpr const char* load_model_name(LoadModel model) noexcept {
    return model == LoadModel::Open ? "open" : "closed";
}

struct RunMetadata {
    std::string tool_version;  // e.g. "mbstorm 0.1.0"
    std::string target;        // "host:port"
    std::uint32_t threads = 0;
    std::uint32_t connections = 0;  // total across threads
    std::uint32_t depth = 0;        // requests in flight per connection (closed loop)
    LoadModel model = LoadModel::Closed;
    double rate_per_second = 0.0;             // open loop target rate (0 for closed)
    std::uint64_t requested_duration_ns = 0;  // what the user asked for
    std::uint64_t measured_duration_ns = 0;   // what was measured (throughput divides by this)
    std::uint64_t warmup_ns = 0;
    std::chrono::system_clock::time_point start_time{};  // wall clock at run start
    bool coordinated_omission_corrected = false;         // closed loop histograms back-filled
    std::vector<std::string> notes;                      // e.g. "embedded slave on 127.0.0.1:15020"
};

struct OperationResult {
    std::string name;                // e.g. "read_holding_registers" or a scenario label
    std::uint8_t function_code = 0;  // Modbus function code
    Histogram latency;
    OutcomeCounters counters;
};

// One scenario stage; the whole-run data is the sum over stages.
struct StageResult {
    std::string name;
    std::uint32_t index = 0;
    std::uint64_t start_offset_ns = 0;
    std::uint64_t end_offset_ns = 0;
    Histogram latency;
    OutcomeCounters counters;
    std::vector<OperationResult> operations;  // optional per-stage, per-operation breakdown
};

// Open loop only: how often the engine could not send on schedule.
struct ScheduleLag {
    std::uint64_t late_sends = 0;  // sends that went out later than their slot + tolerance
    std::uint64_t max_lag_ns = 0;
    std::uint64_t total_lag_ns = 0;  // sum over late sends (mean = total / late_sends)
};

struct ConnectionStats {
    std::uint64_t opened = 0;      // successful connects
    std::uint64_t failed = 0;      // connect attempts that failed
    std::uint64_t reconnects = 0;  // connects after a connection was lost
    std::uint64_t closed_by_peer = 0;
};

// A pass/fail check, e.g. "p99 < 5ms"; filled by the scenario layer.
struct ThresholdResult {
    std::string expression;
    double observed = 0.0;
    std::string observed_text;  // observed value formatted with its unit, e.g. "3.2ms"
    bool passed = false;
};

struct RunResult {
    RunMetadata metadata;
    Histogram latency;         // all operations
    OutcomeCounters counters;  // all operations
    std::vector<OperationResult> operations;
    std::vector<IntervalSummary> timeline;  // from IntervalTimeline::summaries()
    std::uint64_t timeline_interval_ns = 1'000'000'000;
    std::vector<StageResult> stages;  // empty unless a scenario had stages
    ScheduleLag schedule_lag;
    ConnectionStats connections;
    std::vector<ThresholdResult> thresholds;

    // Completed transactions per second over the measured duration.
    double throughput() const noexcept {
        return metadata.measured_duration_ns == 0
                   ? 0.0
                   : static_cast<double>(counters.completed()) * 1e9 /
                         static_cast<double>(metadata.measured_duration_ns);
    }
    bool thresholds_passed() const noexcept {
        for (const auto& t : thresholds)
            if (!t.passed) return false;
        return true;
    }
};

}  // namespace mbstorm::stats
