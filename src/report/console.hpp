// Human-readable output: the final report and the one-line live progress.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>

#include "report/units.hpp"
#include "stats/interval_recorder.hpp"
#include "stats/run_result.hpp"

namespace mbstorm::report {

// Multi-line final report: run summary, throughput, latency percentiles (50, 75, 90, 99,
// 99.9, 99.99, 99.999, max), errors by class, per operation, per stage, thresholds.
std::string format_console_report(const stats::RunResult& result);

struct ProgressSample {
    double elapsed_seconds = 0.0;
    const stats::IntervalSummary* last_interval = nullptr;  // null before the first second
    std::uint64_t total_transactions = 0;
    std::uint64_t total_errors = 0;
    std::uint32_t open_connections = 0;
};

// e.g. "[  12.0s]  48.2k tx/s  p50 210µs  p99 1.20ms  max 3.40ms  errors 0  conns 64"
std::string format_progress_line(const ProgressSample& sample);

// Writes progress lines: on a TTY one line rewritten in place with '\r', otherwise one
// plain line per update (so logs stay readable).
class ProgressPrinter {
  public:
    explicit ProgressPrinter(std::FILE* out);
    ProgressPrinter(std::FILE* out, bool is_tty);
    void update(const ProgressSample& sample);
    // Ends the in-place line (newline) so the final report starts on a fresh line.
    void finish();
    bool is_tty() const noexcept { return is_tty_; }

  private:
    std::FILE* out_;
    bool is_tty_;
    std::size_t last_width_ = 0;
    bool line_open_ = false;
};

}  // namespace mbstorm::report
