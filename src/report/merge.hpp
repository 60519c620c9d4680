// `mbstorm merge`: the runs (shards) of one test, each given as its JSON summary (--json) and
// its interval log (--hlog), combined into one result as if one machine had run the whole
// plan. Counts add; latencies come from the logs' histograms added bucket by bucket, never
// from averaged percentiles; the timeline is lined up on wall-clock time (each run's
// test.measure_start_epoch_s).
//
// What identifies a test: the runs' --test-id (equal, possibly empty) and their plan as the
// JSON shows it (target, load model, operations, requested duration, warm-up, timeline
// interval). Runs differing in either are refused, as are runs given twice (same run id),
// runs without their log (or logs without their run), other histogram settings, and a set
// that is not whole: with shard numbers (test.shard_index / test.shard_count) every index
// 0..count-1 exactly once, otherwise exactly `expect_runs` runs when that is set.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "report/hlog.hpp"
#include "stats/run_result.hpp"
#include "util/error.hpp"

namespace mbstorm::report {

// One run, read from its files.
struct ShardRun {
    std::string json_path;  // for messages
    std::string hlog_path;
    // From the JSON, stages included; histograms empty (they come from the log).
    stats::RunResult summary;
    double measure_start_epoch_s = 0.0;
    int shard_index = -1;  // -1: a plain run
    int shard_count = 0;
    std::uint64_t highest_trackable_ns = 0;
    int significant_digits = 0;
    std::uint64_t lowest_discernible_ns = 0;
    std::vector<std::string> threshold_expressions;  // as the run judged them
    // Exact extremes from the JSON (the logs only know buckets): whole run, then by operation.
    std::uint64_t min_ns = 0, max_ns = 0, latency_count = 0;
    std::vector<std::uint64_t> op_min_ns, op_max_ns;
    std::vector<std::uint64_t> stage_min_ns, stage_max_ns;  // by stage (summary.stages)
    // The log's header; its intervals too unless log_from_file, when merge_shards streams
    // them from hlog_path (read_shards: a decoded interval is a 270 KB histogram).
    Hlog log;
    bool log_from_file = false;
};

// Reads a run's JSON summary (not its log) into out. An error naming the file on failure: Io
// when it cannot be opened, InvalidInput when it is not a summary merge can read.
Error read_shard_summary(const std::string& path, ShardRun& out);

// Sorts files into JSON summaries and interval logs by content, reads them and pairs each
// summary with the log of the same run id. Errors as read_shard_summary's (InvalidInput also
// for files that do not pair up).
Error read_shards(const std::vector<std::string>& files, std::vector<ShardRun>& out);

// The merged run. merge_shards refuses runs that are not one whole test with an InvalidInput
// error saying why.
struct MergeOutcome {
    stats::RunResult run;
    // Threshold expressions the runs carried (identical in every run, else refused), e.g.
    // "p99 < 5ms" or "read: p99 < 5ms"; "plan carried out" is left out (re-derived).
    std::vector<std::string> threshold_expressions;
    std::vector<std::string> warnings;
};

// expect_runs: 0 unless the user said how many runs make the test.
Result<MergeOutcome> merge_shards(std::vector<ShardRun> shards, std::uint32_t expect_runs = 0);

}  // namespace mbstorm::report
