// HdrHistogram interval logs (`run --hlog FILE`), the text format HdrHistogram's own log
// readers and tools (HistogramLogReader, HistogramLogProcessor, HdrHistogramVisualizer) read:
//
//   #[mbstorm interval log: test <id>, run <run id>]            (, shard I/N with run --shard)
//   #[Histogram log format version 1.3]
//   #[StartTime: 1795942311.123 (seconds since epoch), Tue Nov 24 08:51:51 UTC 2026]
//   #[BaseTime: 1795942311.123 (seconds since epoch)]
//   "StartTimestamp","Interval_Length","Interval_Max","Interval_Compressed_Histogram"
//   0.000,1.000,0.532,HISTFAAA...                          all operations
//   Tag=read_holding_registers,0.000,1.000,0.532,HISTFAAA... one operation
//
// Times are seconds from StartTime (the end of warm-up), maxima milliseconds, histograms
// nanoseconds (stats/hdr_encoding.hpp). The writer flushes every interval, so a run that is
// killed leaves a log of its completed intervals.
#pragma once

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <istream>
#include <string>
#include <string_view>
#include <vector>

#include "stats/histogram.hpp"
#include "util/error.hpp"

namespace mbstorm::report {

// A tag may hold no comma or white space (they separate a line's fields): those become '_'.
std::string hlog_tag(std::string_view name);
// The tag of a stage's whole histogram, written once per stage at the end of a staged run
// (start and length the stage's), so that `mbstorm merge` can rebuild the per-stage table.
std::string hlog_stage_tag(std::uint32_t stage_index);
// The stage index of such a tag, or 0 when `tag` is not one.
std::uint32_t stage_of_hlog_tag(std::string_view tag);

class HlogWriter {
  public:
    HlogWriter() = default;
    HlogWriter(const HlogWriter&) = delete;
    HlogWriter& operator=(const HlogWriter&) = delete;
    ~HlogWriter();

    // Creates (truncates) path; comment: the first line's text, e.g. the run's identity. An Io
    // error "<path>: <reason>" when it cannot.
    Error open(const std::string& path, std::string comment);
    // The header: written once, before the first interval (or at close when none came).
    void start(std::chrono::system_clock::time_point start_time);
    // One line; tag empty for the untagged (all operations) line.
    void write_interval(std::string_view tag, double start_s, double length_s,
                        const stats::Histogram& histogram);
    // Ends the interval's lines: flushed to the file.
    void end_interval();
    // Flushes and closes; an Io error (the reason, no path) when any write failed.
    Error close();

    bool is_open() const noexcept { return file_ != nullptr; }
    bool started() const noexcept { return started_; }

  private:
    std::FILE* file_ = nullptr;
    std::string comment_;
    bool started_ = false;
    bool failed_ = false;
};

struct HlogInterval {
    std::string tag;       // empty: untagged
    double start_s = 0.0;  // from the log's start time
    double length_s = 0.0;
    double max_ms = 0.0;
    stats::Histogram histogram;
};

struct Hlog {
    std::vector<std::string> comments;  // '#' lines without the '#'
    bool has_start_time = false;
    double start_time_s = 0.0;  // seconds since the epoch
    bool has_base_time = false;
    double base_time_s = 0.0;
    std::vector<HlogInterval> intervals;

    // Seconds since the epoch of an interval's start, as HdrHistogram's reader computes it.
    double absolute_start_s(const HlogInterval& interval) const;
};

// Reads a log one interval line at a time, so that a reader of a long log holds one decoded
// histogram instead of all of them (an 8-hour log at 1 s has some 60,000 lines of 270 KB
// each once decoded).
class HlogReader {
  public:
    explicit HlogReader(std::istream& in);
    // The next interval line, decoded into out; header lines met on the way go to header().
    // False at the end of the log or on a bad line (error() then says which).
    bool next(HlogInterval& out);
    // Reads the header lines only (up to the first interval line). False on a bad line.
    bool read_header();
    // The line that starts at offset (a line_offset() of an earlier next()): a second look
    // at a line without keeping it. Its line number in errors is not the file's.
    bool read_at(std::uint64_t offset, HlogInterval& out);
    // Where the line next() returned last starts, in bytes from the start of the stream.
    std::uint64_t line_offset() const noexcept { return line_offset_; }
    std::size_t line_number() const noexcept { return line_number_; }
    Hlog& header() noexcept { return header_; }
    // Why next() or read_header() stopped early: InvalidInput naming the line ("line 7: ..."),
    // or success at the end of the log.
    const Error& error() const noexcept { return error_; }

  private:
    std::istream& in_;
    Hlog header_;
    std::string line_;
    Error error_;
    std::uint64_t line_offset_ = 0;
    std::size_t line_number_ = 0;
};

// Parses a log (as read_hlog does a file). InvalidInput errors name the line: "line 7: ...";
// read_hlog's name the file too ("run.hlog: line 7: ..."), or are Io when it cannot be read.
Result<Hlog> parse_hlog(std::string_view text);
Result<Hlog> read_hlog(const std::string& path);

// Which run wrote a log: its first line's text (HlogWriter::open's comment).
struct HlogIdentity {
    std::string test_id;  // "-" when the run had no --test-id
    std::string run_id;
    std::uint32_t shard_index = 0;
    std::uint32_t shard_count = 0;  // 0: not a shard
};
std::string hlog_identity_text(const HlogIdentity& identity);
// False when no comment of the log is such a line.
bool find_hlog_identity(const Hlog& log, HlogIdentity& out);

}  // namespace mbstorm::report
