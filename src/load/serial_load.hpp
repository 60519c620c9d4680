// `run --serial`: the load test on a serial line. A bus carries one transaction at a time, so
// this is one blocking master (load/serial_master.hpp) on a thread of its own, in place of the
// engine's io_uring workers: driven by the plan's operations, closed loop or paced by the rate
// (the stages' rates too), it records into the same interval timeline, stage results and live
// cells as a worker does, so the engine's thread watches, streams and reports both alike.
#pragma once

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "load/engine.hpp"
#include "load/plan.hpp"
#include "load/serial_master.hpp"
#include "load/stage_schedule.hpp"
#include "stats/interval_recorder.hpp"
#include "stats/run_result.hpp"
#include "util/error.hpp"

namespace mbstorm::load {

struct SerialRunSetup {
    const Plan* plan = nullptr;  // plan.serial.device is set and the plan is valid
    const EngineOptions* options = nullptr;
    const StageSchedule* schedule = nullptr;  // empty without stages
    stats::IntervalTimeline* timeline = nullptr;
    LiveWorkerCells* live = nullptr;  // null without --metrics-listen
    std::int64_t start_ns = 0;        // the first request (warm-up first)
    std::int64_t measure_start_ns = 0;
    std::int64_t end_ns = INT64_MAX;  // INT64_MAX: when the transactions are done
    const std::atomic<bool>* abort = nullptr;
};

class SerialRunner {
  public:
    explicit SerialRunner(const SerialRunSetup& setup);

    // Opens the line, or says why not.
    Error open();
    std::string describe() const { return master_.describe(); }
    // The run's thread: until the end, the count, a stop or a failed line.
    void run() noexcept;
    // 1 while the line is open (the engine's thread reads it as "open connections").
    std::uint32_t open_connections() const noexcept {
        return open_.load(std::memory_order_relaxed);
    }

    // What was measured, read after run() returned.
    std::vector<stats::OperationResult> operations;
    stats::OutcomeCounters counters;
    stats::Histogram service_time;           // open loop: answers timed from their actual send
    std::vector<stats::StageResult> stages;  // sized like the schedule's stages
    stats::LagCounts target_lag;             // open loop: sends the busy line delayed
    std::uint64_t bad_checks = 0;            // answers whose CRC/LRC failed
    Error fatal_error;                       // the tty failed
    std::int64_t finished_ns = 0;

  private:
    // How long until the next request may go out (open loop), or 0 for at once; -1 while the
    // schedule wants no load (a stage with rate 0 or no connection).
    std::int64_t pace(std::int64_t now) noexcept;
    void record(const RequestInfo& info, stats::Outcome outcome, std::uint8_t exception, bool timed,
                std::uint64_t latency_ns, std::size_t sent_bytes, std::size_t received_bytes,
                std::int64_t from) noexcept;

    SerialRunSetup setup_;
    SerialMaster master_;
    stats::IntervalRecorder interval_;
    std::atomic<std::uint32_t> open_{0};
    bool open_loop_ = false;
    std::int64_t next_send_ = 0;  // open loop: the intended send time of the next request
};

}  // namespace mbstorm::load
