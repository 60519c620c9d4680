// `run --timeline FILE`: the run's timeline as JSON Lines, one object per interval (the keys of
// --json's timeline.intervals[], plus duration_s, epoch_s, test and run_id), each written and
// flushed as soon as the run has finished the interval, so that a run that is killed keeps
// every interval it completed.
#pragma once

#include <chrono>
#include <cstdio>
#include <string>

#include "stats/interval_recorder.hpp"
#include "util/error.hpp"

namespace mbstorm::report {

// One line (with its newline). measure_start: wall-clock time of offset 0 (end of warm-up).
std::string format_timeline_line(const stats::IntervalSummary& interval,
                                 std::chrono::system_clock::time_point measure_start,
                                 const std::string& test_id, const std::string& run_id);

class TimelineWriter {
  public:
    TimelineWriter() = default;
    TimelineWriter(const TimelineWriter&) = delete;
    TimelineWriter& operator=(const TimelineWriter&) = delete;
    ~TimelineWriter();

    // Creates (truncates) path; an Io error "<path>: <reason>" when it cannot.
    Error open(const std::string& path, std::string test_id, std::string run_id);
    // Writes and flushes one interval's line.
    void write(const stats::IntervalSummary& interval,
               std::chrono::system_clock::time_point measure_start);
    // An Io error (the reason, no path) when any write failed.
    Error close();
    bool is_open() const noexcept { return file_ != nullptr; }

  private:
    std::FILE* file_ = nullptr;
    std::string test_id_, run_id_;
    bool failed_ = false;
};

}  // namespace mbstorm::report
