// What `mbstorm run` prints while it runs and writes when it ends.
#pragma once

#include <CLI/CLI.hpp>

#include <cstdint>
#include <cstdio>
#include <string>

#include "load/engine.hpp"
#include "report/console.hpp"
#include "util/error.hpp"

namespace mbstorm::cli {

// Report files; "-" is standard output. At most one of them (with a scenario's JUnit XML) may
// be "-", and then the console report goes to stderr so that stdout holds only that file.
struct OutputFiles {
    std::string json, hdr, html;
    std::string hlog;      // HdrHistogram interval log, written as the run goes (not stdout)
    std::string timeline;  // JSON Lines, one object per interval, written as the run goes
    // --test-id: names the test the run belongs to in the JSON and the interval log, so that
    // `mbstorm merge` can refuse a run of another test.
    std::string test_id;
    // --metrics-listen HOST:PORT: serve live metrics (Prometheus) while the run goes.
    std::string metrics_listen;
    // --metrics-linger: after the run, keep /metrics up with the final values until a scrape
    // has taken them, for at most this long (0: the endpoint ends with the run).
    std::uint64_t metrics_linger_ns = 0;
    // JUnit XML of a scenario's thresholds: not a flag of add_output_options, set from the
    // scenario request with the scenario's name as the suite.
    std::string junit;
    std::string junit_suite;
    bool uses_stdout() const { return json == "-" || hdr == "-" || html == "-" || junit == "-"; }
};

// None, or the usage error for more than one output on stdout.
Error stdout_conflict(const OutputFiles& files);

void add_output_options(CLI::App* cmd, OutputFiles& files);
// run only: --hlog and --test-id.
void add_run_identity_options(CLI::App* cmd, OutputFiles& files);

// Live progress on stderr: one updating line on a terminal, plain lines otherwise.
class LiveProgress {
  public:
    LiveProgress(std::FILE* out, bool quiet) : printer_(out), quiet_(quiet) {}
    void update(const load::ProgressSnapshot& s);
    void finish() {
        if (!quiet_) printer_.finish();
    }

  private:
    report::ProgressPrinter printer_;
    bool quiet_;
    stats::IntervalSummary last_{};
};

// Prints the final report and writes the requested files (the formats are report/'s; this is
// the one place that writes run's files). Returns the exit code: 2 when the run could not start
// or a file could not be written, 1 when the run failed (judge_run), 0 otherwise (thresholds
// are the scenario layer's business). The JUnit XML is written even when the run could not
// start, so that CI shows the failure.
int report_run(load::LoadResult& result, const OutputFiles& files);
// 1 (with a line on stderr) when no transaction succeeded or the target was lost and did not
// come back; 0 otherwise.
int judge_run(const load::LoadResult& result);

}  // namespace mbstorm::cli
