#include "report/merge.hpp"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>

#include "../support/sanitizers.hpp"

namespace mbstorm::report {
namespace {

constexpr std::uint64_t kSecond = 1'000'000'000;

// A run of `intervals` seconds starting at `start_s` (epoch seconds), operations "read" and
// "write", latencies drawn from rng and also fed to `all` (the one-machine reference).
ShardRun make_shard(const std::string& run_id, double start_s, int intervals, std::mt19937_64& rng,
                    stats::Histogram& all, stats::Histogram& all_read) {
    ShardRun s;
    s.json_path = run_id + ".json";
    s.hlog_path = run_id + ".hlog";
    auto& m = s.summary.metadata;
    m.test_id = "t";
    m.run_id = run_id;
    m.target = "127.0.0.1:502";
    m.threads = 1;
    m.connections = 4;
    m.depth = 2;
    m.requested_duration_ns = intervals * kSecond;
    m.measured_duration_ns = intervals * kSecond;
    s.summary.timeline_interval_ns = kSecond;
    s.measure_start_epoch_s = start_s;
    s.significant_digits = 3;
    s.lowest_discernible_ns = 1;
    s.highest_trackable_ns = stats::Histogram::kOneHourNs;
    s.summary.operations.resize(2);
    s.summary.operations[0].name = "read";
    s.summary.operations[0].function_code = 3;
    s.summary.operations[1].name = "write";
    s.summary.operations[1].function_code = 16;
    s.op_min_ns.assign(2, UINT64_MAX);
    s.op_max_ns.assign(2, 0);
    s.min_ns = UINT64_MAX;
    s.log.has_start_time = true;
    s.log.start_time_s = start_s;
    for (int k = 0; k < intervals; ++k) {
        HlogInterval untagged, read, write;
        untagged.start_s = read.start_s = write.start_s = k;
        untagged.length_s = read.length_s = write.length_s = 1;
        read.tag = "read";
        write.tag = "write";
        stats::IntervalSummary iv;
        iv.index = static_cast<std::uint64_t>(k);
        iv.start_offset_ns = k * kSecond;
        for (int i = 0; i < 1000; ++i) {
            const std::uint64_t v = 1000 + rng() % 50'000'000;
            const bool is_read = i % 4 != 0;
            untagged.histogram.record(v);
            (is_read ? read : write).histogram.record(v);
            all.record(v);
            if (is_read) all_read.record(v);
            auto& op = s.summary.operations[is_read ? 0 : 1];
            op.counters.record(stats::Outcome::Ok);
            ++op.counters.transactions_sent;
            s.summary.counters.record(stats::Outcome::Ok);
            ++s.summary.counters.transactions_sent;
            const std::size_t o = is_read ? 0 : 1;
            s.op_min_ns[o] = std::min(s.op_min_ns[o], v);
            s.op_max_ns[o] = std::max(s.op_max_ns[o], v);
            s.min_ns = std::min(s.min_ns, v);
            s.max_ns = std::max(s.max_ns, v);
            ++s.latency_count;
            ++iv.transactions;
        }
        s.summary.timeline.push_back(iv);
        s.log.intervals.push_back(std::move(untagged));
        s.log.intervals.push_back(std::move(read));
        s.log.intervals.push_back(std::move(write));
    }
    return s;
}

void expect_same_histogram(const stats::Histogram& a, const stats::Histogram& b) {
    ASSERT_EQ(a.total_count(), b.total_count());
    for (std::size_t i = 0; i < a.counts_length(); ++i)
        ASSERT_EQ(a.count_at_index(i), b.count_at_index(i)) << "index " << i;
    EXPECT_EQ(a.min(), b.min());
    EXPECT_EQ(a.max(), b.max());
    for (double p : {0.0, 50.0, 90.0, 99.0, 99.9, 99.99, 100.0})
        EXPECT_EQ(a.value_at_percentile(p), b.value_at_percentile(p)) << "p" << p;
}

TEST(Merge, CountsAddAndPercentilesAreThoseOfOneHistogramFedEveryValue) {
    std::mt19937_64 rng(7);
    stats::Histogram all, all_read;
    std::vector<ShardRun> shards;
    shards.push_back(make_shard("a", 1000.0, 3, rng, all, all_read));
    shards.push_back(make_shard("b", 1000.0, 3, rng, all, all_read));
    shards.push_back(make_shard("c", 1000.0, 3, rng, all, all_read));
    const Result<MergeOutcome> merged = merge_shards(shards);
    ASSERT_TRUE(merged.ok()) << merged.error().text();
    EXPECT_TRUE(merged->warnings.empty());
    const auto& run = merged->run;
    EXPECT_EQ(run.metadata.merged_runs, 3u);
    EXPECT_EQ(run.metadata.connections, 12u);
    EXPECT_EQ(run.counters.ok(), 9000u);
    EXPECT_EQ(run.counters.transactions_sent, 9000u);
    expect_same_histogram(run.latency, all);
    ASSERT_EQ(run.operations.size(), 2u);
    EXPECT_EQ(run.operations[0].counters.ok(), 6750u);
    expect_same_histogram(run.operations[0].latency, all_read);
    EXPECT_EQ(run.operations[1].latency.total_count(), 2250u);
    ASSERT_EQ(run.timeline.size(), 3u);
    for (const auto& iv : run.timeline) {
        EXPECT_EQ(iv.transactions, 3000u);
        EXPECT_EQ(iv.latency_count, 3000u);
    }
    EXPECT_EQ(run.metadata.measured_duration_ns, 3 * kSecond);
}

TEST(Merge, TlsCountersAddUpAndTheLongestHandshakeIsTheLongestOfAll) {
    std::mt19937_64 rng(7);
    stats::Histogram all, all_read;
    std::vector<ShardRun> shards;
    for (const char* id : {"a", "b"}) {
        shards.push_back(make_shard(id, 1000.0, 1, rng, all, all_read));
        auto& c = shards.back().summary.connections;
        c.tls_handshakes = 4;
        c.tls_resumed = 2;
        c.tls_handshake_ns_total = 4'000'000;
        c.tls_handshake_ns_max = id[0] == 'a' ? 1'500'000 : 2'500'000;
        c.tls_handshake_failures = 1;
        c.tls_offloaded = 3;
        c.tls_offload_errors = 1;
    }
    const Result<MergeOutcome> merged = merge_shards(shards);
    ASSERT_TRUE(merged.ok()) << merged.error().text();
    const auto& c = merged->run.connections;
    EXPECT_EQ(c.tls_handshakes, 8u);
    EXPECT_EQ(c.tls_resumed, 4u);
    EXPECT_EQ(c.tls_handshake_ns_total, 8'000'000u);
    EXPECT_EQ(c.tls_handshake_ns_max, 2'500'000u);
    EXPECT_EQ(c.tls_handshake_failures, 2u);
    EXPECT_EQ(c.tls_offloaded, 6u);
    EXPECT_EQ(c.tls_offload_errors, 2u);
}

TEST(Merge, TimelineLinesUpOnWallClockTime) {
    std::mt19937_64 rng(8);
    stats::Histogram all, all_read;
    std::vector<ShardRun> shards;
    shards.push_back(make_shard("late", 1002.2, 2, rng, all, all_read));  // 2.2 s after "early"
    shards.back().summary.metadata.requested_duration_ns = 3 * kSecond;  // the same plan, cut short
    shards.push_back(make_shard("early", 1000.0, 3, rng, all, all_read));
    const Result<MergeOutcome> merged = merge_shards(shards);
    ASSERT_TRUE(merged.ok()) << merged.error().text();
    const auto& tl = merged->run.timeline;
    // early: 0, 1, 2; late's intervals start at 2.2 and 3.2: their middles fall in 2 and 3.
    ASSERT_EQ(tl.size(), 4u);
    EXPECT_EQ(tl[0].transactions, 1000u);
    EXPECT_EQ(tl[1].transactions, 1000u);
    EXPECT_EQ(tl[2].transactions, 2000u);
    EXPECT_EQ(tl[2].latency_count, 2000u);
    EXPECT_EQ(tl[3].transactions, 1000u);
    // From the first start to the last end: 4.2 s.
    EXPECT_NEAR(static_cast<double>(merged->run.metadata.measured_duration_ns), 4.2e9, 1e3);
    EXPECT_EQ(tl[3].duration_ns, merged->run.metadata.measured_duration_ns - 3 * kSecond);
    expect_same_histogram(merged->run.latency, all);
}

TEST(Merge, RefusesWhatIsNotOneWholeTest) {
    std::mt19937_64 rng(9);
    stats::Histogram all, all_read;
    auto two = [&] {
        std::vector<ShardRun> v;
        v.push_back(make_shard("a", 1000.0, 1, rng, all, all_read));
        v.push_back(make_shard("b", 1000.0, 1, rng, all, all_read));
        return v;
    };
    auto refused = [](std::vector<ShardRun> v, std::uint32_t expect = 0) {
        const Result<MergeOutcome> r = merge_shards(std::move(v), expect);
        EXPECT_FALSE(r.ok());
        return r.error().text();
    };
    auto v = two();
    v[1].summary.metadata.run_id = "a";
    EXPECT_EQ(refused(v), "duplicate run: a.json and b.json are the same run (a)");

    v = two();
    v[1].summary.metadata.test_id = "other";
    EXPECT_EQ(refused(v),
              "b.json (run b) is from another test: test id 'other', a.json (run a) has 't' (run "
              "--test-id)");

    v = two();
    v[1].summary.metadata.target = "127.0.0.1:503";
    EXPECT_NE(refused(v).find("b.json (run b) is from another test: its plan is target "
                              "127.0.0.1:503"),
              std::string::npos);

    v = two();
    v[1].summary.operations[1].name = "write2";
    EXPECT_NE(refused(v).find("is from another test"), std::string::npos);

    v = two();
    v[1].significant_digits = 2;
    EXPECT_NE(refused(v).find("different histogram settings: b.json (run b) has 2 significant "
                              "digits"),
              std::string::npos);

    v = two();
    v[0].threshold_expressions = {"p99 < 5ms"};
    EXPECT_NE(refused(v).find("its thresholds differ"), std::string::npos);

    v = two();
    EXPECT_EQ(refused(v, 3), "2 runs given, --expect says the test has 3: missing runs");
    EXPECT_TRUE(merge_shards(two(), 2).ok());

    // Numbered shards: every index once.
    v = two();
    for (auto& s : v) s.shard_count = 3;
    v[0].shard_index = 0;
    v[1].shard_index = 2;
    EXPECT_EQ(refused(v), "missing shards: 2 of 3 given, shard 1 missing");
    v[1].shard_index = 0;
    EXPECT_EQ(refused(v), "duplicate shard 0: a.json (run a) and b.json (run b)");
    v[1].shard_count = 2;
    EXPECT_NE(refused(v).find("disagree on the shard count"), std::string::npos);
    // A plain run among shards (or a shard among plain runs) is not part of the set.
    v = two();
    v[0].shard_index = 0;
    v[0].shard_count = 2;
    EXPECT_EQ(refused(v),
              "b.json (run b) is not a shard, a.json (run a) is shard 0/2: shards merge only with "
              "the other shards of their test");

    EXPECT_EQ(refused({}), "no runs to merge");
}

// Two stages of 1 s and 2 s over a run of make_shard's: each stage's counts from the JSON and its
// histogram, one "stage:N" line of the log, as `run --hlog` writes them at the end.
void add_stages(ShardRun& s, std::mt19937_64& rng, std::vector<stats::Histogram>& all_by_stage) {
    all_by_stage.resize(2);
    for (std::uint32_t k = 1; k <= 2; ++k) {
        stats::StageResult st;
        st.index = k;
        st.name = k == 1 ? "warm" : "peak";
        st.start_offset_ns = k == 1 ? 0 : kSecond;
        st.end_offset_ns = k == 1 ? kSecond : 3 * kSecond;
        st.rate_from = st.rate_to = k * 100.0;
        st.connections_from = st.connections_to = 4;
        HlogInterval line;
        line.tag = hlog_stage_tag(k);
        line.start_s = static_cast<double>(st.start_offset_ns) / 1e9;
        line.length_s = static_cast<double>(st.end_offset_ns - st.start_offset_ns) / 1e9;
        std::uint64_t lo = UINT64_MAX, hi = 0;
        for (int i = 0; i < 500 * static_cast<int>(k); ++i) {
            const std::uint64_t v = 2000 + rng() % 9'000'000;
            line.histogram.record(v);
            all_by_stage[k - 1].record(v);
            st.counters.record(stats::Outcome::Ok);
            ++st.counters.transactions_sent;
            lo = std::min(lo, v);
            hi = std::max(hi, v);
        }
        s.stage_min_ns.push_back(lo);
        s.stage_max_ns.push_back(hi);
        s.summary.stages.push_back(std::move(st));
        s.log.intervals.push_back(std::move(line));
    }
}

TEST(Merge, StagesAddUpStageByStageFromTheLogsStageLines) {
    std::mt19937_64 rng(11);
    stats::Histogram all, all_read;
    std::vector<stats::Histogram> by_stage;
    std::vector<ShardRun> v;
    for (const char* id : {"a", "b"}) {
        v.push_back(make_shard(id, 1000.0, 3, rng, all, all_read));
        add_stages(v.back(), rng, by_stage);
    }
    const Result<MergeOutcome> r = merge_shards(v);
    ASSERT_TRUE(r.ok()) << r.error().text();
    EXPECT_TRUE(r->warnings.empty()) << r->warnings.front();
    ASSERT_EQ(r->run.stages.size(), 2u);
    const auto& peak = r->run.stages[1];
    EXPECT_EQ(peak.name, "peak");
    EXPECT_EQ(peak.counters.ok(), 2000u);
    EXPECT_EQ(peak.rate_to, 400.0);  // each shard's share, added
    EXPECT_EQ(peak.connections_to, 8u);
    EXPECT_EQ(peak.start_offset_ns, kSecond);
    expect_same_histogram(r->run.stages[0].latency, by_stage[0]);
    expect_same_histogram(peak.latency, by_stage[1]);
    // The stage lines are not latencies of the whole run (no "log holds more" warning above)
    // nor of an operation.
    EXPECT_EQ(r->run.latency.total_count(), 6000u);
    expect_same_histogram(r->run.latency, all);

    // A run whose log has no stage lines (an older mbstorm): no table, and a warning.
    std::erase_if(v[1].log.intervals,
                  [](const HlogInterval& line) { return stage_of_hlog_tag(line.tag) != 0; });
    const Result<MergeOutcome> older = merge_shards(v);
    ASSERT_TRUE(older.ok());
    EXPECT_TRUE(older->run.stages.empty());
    ASSERT_EQ(older->warnings.size(), 1u);
    EXPECT_NE(older->warnings[0].find("no per-stage table: the interval log of b.json"),
              std::string::npos)
        << older->warnings[0];
}

TEST(Merge, StageTagsRoundTrip) {
    EXPECT_EQ(hlog_stage_tag(3), "stage:3");
    EXPECT_EQ(stage_of_hlog_tag("stage:3"), 3u);
    EXPECT_EQ(stage_of_hlog_tag("stage:"), 0u);
    EXPECT_EQ(stage_of_hlog_tag("stage:3x"), 0u);
    EXPECT_EQ(stage_of_hlog_tag("read"), 0u);
    EXPECT_EQ(stage_of_hlog_tag(""), 0u);
}

// Two 2 s runs one after the other (issue #29: merged into "duration 4.0 s" and half the
// throughput, silently).
TEST(Merge, WarnsWhenTheRunsDidNotRunAtTheSameTime) {
    std::mt19937_64 rng(11);
    stats::Histogram all, all_read;
    std::vector<ShardRun> v;
    v.push_back(make_shard("first", 1000.0, 2, rng, all, all_read));
    v.push_back(make_shard("second", 1002.5, 2, rng, all, all_read));
    const Result<MergeOutcome> apart = merge_shards(v);
    ASSERT_TRUE(apart.ok()) << apart.error().text();
    ASSERT_EQ(apart->warnings.size(), 1u);
    EXPECT_EQ(apart->warnings[0],
              "the runs did not all run at the same time: 4.5 s from the first start to the last "
              "end, 0.0 s with every run going, 0.5 s with none; the duration and throughput "
              "count that whole span (start the runs of one test together: run --start-at)");
    // Started together: nothing to say.
    v[1] = make_shard("second", 1000.0, 2, rng, all, all_read);
    EXPECT_TRUE(merge_shards(v)->warnings.empty());
}

TEST(Merge, WarnsWhenALogHoldsFewerLatenciesThanItsSummary) {
    std::mt19937_64 rng(10);
    stats::Histogram all, all_read;
    std::vector<ShardRun> v;
    v.push_back(make_shard("a", 1000.0, 2, rng, all, all_read));
    v[0].log.intervals.resize(3);  // as if killed after its first interval
    const Result<MergeOutcome> r = merge_shards(v);
    ASSERT_TRUE(r.ok());
    ASSERT_EQ(r->warnings.size(), 1u);
    EXPECT_NE(r->warnings[0].find("its interval log holds 1000 latencies, its JSON 2000"),
              std::string::npos);
}

}  // namespace
// A shard's counts and times are whole numbers that fit their fields: anything else refuses the
// file, saying what was wrong. fuzz_merge_json found an outcome count of 3.3e26 converted to a
// 64-bit count (undefined behaviour, UBSan) after 8 minutes.
TEST(Merge, RefusesACountThatIsNotAWholeNumberThatFits) {
    std::ifstream in(std::string(MBSTORM_SOURCE_DIR) + "/fuzz/corpus/merge_json/1.json");
    const nlohmann::json real = nlohmann::json::parse(in);
    const std::string path = (std::filesystem::temp_directory_path() /
                              ("merge-count-" + std::to_string(::getpid()) + ".json"))
                                 .string();
    auto read_with = [&](const nlohmann::json& count) {
        nlohmann::json doc = real;
        doc["operations"][0]["outcomes"]["exception"] = count;
        std::ofstream(path) << doc.dump();
        ShardRun run;
        Error error = read_shard_summary(path, run);
        std::remove(path.c_str());
        return error;
    };
    const Error good = read_with(7);
    EXPECT_TRUE(good.ok()) << good.text();
    for (const nlohmann::json& bad :
         {nlohmann::json(3.3e26), nlohmann::json(-1), nlohmann::json(1.5)}) {
        const Error error = read_with(bad);
        EXPECT_EQ(error.code(), ErrorCode::InvalidInput) << bad.dump();
        EXPECT_NE(error.message().find("is not a whole number"), std::string::npos) << error.text();
    }
}

namespace {

using test::kAddressSanitizer;

constexpr int kMergedExit = 0, kRefusedExit = 2, kOutOfMemoryExit = 3;

// merge_shards(runs) in a child process limited to `megabytes` of address space: kMergedExit,
// kRefusedExit or kOutOfMemoryExit (bad_alloc). Before issue #31 these inputs allocated a
// 270 KB histogram per timeline interval until the machine ran out: the limit keeps a
// regression from taking the machine with it.
int merge_limited(const std::vector<ShardRun>& runs, decltype(RLIMIT_AS) resource, rlim_t value) {
    const pid_t child = ::fork();
    if (child == 0) {
        const rlimit limit{value, value};
        ::setrlimit(resource, &limit);
        try {
            ::_exit(merge_shards(runs).ok() ? kMergedExit : kRefusedExit);
        } catch (const std::bad_alloc&) {
            ::_exit(kOutOfMemoryExit);
        }
    }
    int status = 0;
    ::waitpid(child, &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

int merge_within(const std::vector<ShardRun>& runs, rlim_t megabytes) {
    return merge_limited(runs, RLIMIT_AS, megabytes << 20);
}

std::vector<ShardRun> two_runs(double second_start_s, int intervals = 2) {
    std::mt19937_64 rng(31);
    stats::Histogram all, all_read;
    std::vector<ShardRun> v;
    v.push_back(make_shard("a", 1000.0, intervals, rng, all, all_read));
    v.push_back(make_shard("b", second_start_s, intervals, rng, all, all_read));
    return v;
}

}  // namespace

// Issue #31: two legitimate runs a day apart (or one start time edited a day later) made the
// merge allocate a histogram for each of the 86,400 empty intervals between them (23 GB). They
// merge now with the overlap warning, every interval of the span in the timeline and a
// histogram only while an interval with latencies is being summarized.
TEST(Merge, RunsADayApartMergeInBoundedMemory) {
    const auto v = two_runs(1000.0 + 86'400.0);
    if (!kAddressSanitizer) {
        ASSERT_EQ(merge_within(v, 1024), kMergedExit);
    }
    const Result<MergeOutcome> r = merge_shards(v);
    ASSERT_TRUE(r.ok()) << r.error().text();
    ASSERT_EQ(r->warnings.size(), 1u);
    EXPECT_NE(r->warnings[0].find("did not all run at the same time"), std::string::npos);
    ASSERT_EQ(r->run.timeline.size(), 86'402u);
    std::size_t with_latencies = 0;
    for (const auto& iv : r->run.timeline) with_latencies += iv.latency_count != 0 ? 1 : 0;
    EXPECT_EQ(with_latencies, 4u);
    EXPECT_EQ(r->run.timeline[86'400].latency_count, 1000u);
    EXPECT_EQ(r->run.timeline[86'400].transactions, 1000u);
    EXPECT_EQ(r->run.timeline[5].transactions, 0u);
    EXPECT_EQ(r->run.latency.total_count(), 4000u);
}

// A span no timeline should hold (a start time edited a year on, an interval of 1 µs) is
// refused with the reason, not allocated for.
TEST(Merge, RefusesASpanOfMoreIntervalsThanATimelineHolds) {
    const auto year = two_runs(1000.0 + 365 * 86'400.0);
    if (!kAddressSanitizer) {
        ASSERT_EQ(merge_within(year, 1024), kRefusedExit);
    }
    const Result<MergeOutcome> r = merge_shards(year);
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.error().text().find("more than the 1000000 a merged timeline holds"),
              std::string::npos)
        << r.error().text();
    auto micro = two_runs(1000.0);
    for (auto& s : micro) s.summary.timeline_interval_ns = 1000;
    EXPECT_FALSE(merge_shards(micro).ok());
}

// A log line far outside its run (an edited start: 1e6 s in a 2 s run) made the timeline a
// million intervals long; a JSON interval likewise. Both are refused naming the file.
TEST(Merge, RefusesALineOutsideItsRunsOwnDuration) {
    auto v = two_runs(1000.0);
    v[1].log.intervals[3].start_s = 1e6;  // b's second untagged line
    if (!kAddressSanitizer) {
        ASSERT_EQ(merge_within(v, 1024), kRefusedExit);
    }
    Result<MergeOutcome> r = merge_shards(v);
    ASSERT_FALSE(r.ok());
    EXPECT_NE(
        r.error().text().find("b.hlog: a line of 1.000 s starting at 1000000.000 s, outside the "
                              "run's own 2.000 s"),
        std::string::npos)
        << r.error().text();
    v = two_runs(1000.0);
    v[0].summary.timeline[1].start_offset_ns = 1'000'000 * kSecond;
    r = merge_shards(v);
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.error().text().find("a.json: timeline interval 1 starts at 1000000.000 s"),
              std::string::npos)
        << r.error().text();
}

// mbstorm merge streams each log from its file (read_shards): the result is the one the
// decoded logs give.
TEST(Merge, LogsStreamedFromTheirFilesMergeAsTheirDecodedLines) {
    auto in_memory = two_runs(1000.0, 3);
    auto streamed = in_memory;
    const auto dir = std::filesystem::temp_directory_path();
    for (auto& s : streamed) {
        s.hlog_path = (dir / ("merge-stream-" + std::to_string(::getpid()) + s.hlog_path)).string();
        HlogWriter writer;
        ASSERT_TRUE(writer.open(s.hlog_path, "mbstorm interval log: test t, run x").ok());
        writer.start(std::chrono::system_clock::time_point{});
        for (const auto& line : s.log.intervals)
            writer.write_interval(line.tag, line.start_s, line.length_s, line.histogram);
        const Error closed = writer.close();
        ASSERT_TRUE(closed.ok()) << closed.text();
        s.log.intervals.clear();
        s.log_from_file = true;
    }
    const Result<MergeOutcome> a = merge_shards(in_memory), b = merge_shards(streamed);
    for (const auto& s : streamed) std::remove(s.hlog_path.c_str());
    ASSERT_TRUE(a.ok() && b.ok()) << a.error().text() << b.error().text();
    expect_same_histogram(b->run.latency, a->run.latency);
    expect_same_histogram(b->run.operations[1].latency, a->run.operations[1].latency);
    ASSERT_EQ(b->run.timeline.size(), 3u);
    for (std::size_t k = 0; k < 3; ++k) {
        EXPECT_EQ(b->run.timeline[k].p99_ns, a->run.timeline[k].p99_ns);
        EXPECT_EQ(b->run.timeline[k].latency_count, 2000u);
    }
    EXPECT_EQ(b->warnings, a->warnings);
}

// Past 64 runs the logs are not all held open while their lines are read again in time order
// (a descriptor per run of a 1000-shard test is too many): each is reopened per line, with the
// same result, and 70 runs merge with 32 descriptors.
TEST(Merge, ManyStreamedLogsMergeAsTheirDecodedLines) {
    std::mt19937_64 rng(3);
    stats::Histogram all, all_read;
    std::vector<ShardRun> in_memory;
    for (int i = 0; i < 70; ++i)
        in_memory.push_back(make_shard("m" + std::to_string(i), 1000.0, 2, rng, all, all_read));
    auto streamed = in_memory;
    for (auto& s : streamed) {
        s.hlog_path = (std::filesystem::temp_directory_path() /
                       ("merge-many-" + std::to_string(::getpid()) + s.hlog_path))
                          .string();
        HlogWriter writer;
        ASSERT_TRUE(writer.open(s.hlog_path, "mbstorm interval log: test t, run x").ok());
        writer.start(std::chrono::system_clock::time_point{});
        for (const auto& line : s.log.intervals)
            writer.write_interval(line.tag, line.start_s, line.length_s, line.histogram);
        const Error closed = writer.close();
        ASSERT_TRUE(closed.ok()) << closed.text();
        s.log.intervals.clear();
        s.log_from_file = true;
    }
    const int with_32_descriptors = merge_limited(streamed, RLIMIT_NOFILE, 32);
    const Result<MergeOutcome> a = merge_shards(in_memory), b = merge_shards(streamed);
    for (const auto& s : streamed) std::remove(s.hlog_path.c_str());
    EXPECT_EQ(with_32_descriptors, kMergedExit);
    ASSERT_TRUE(a.ok() && b.ok()) << a.error().text() << b.error().text();
    expect_same_histogram(b->run.latency, all);
    ASSERT_EQ(b->run.timeline.size(), 2u);
    EXPECT_EQ(b->run.timeline[1].latency_count, 70'000u);
    EXPECT_EQ(b->run.timeline[1].p99_ns, a->run.timeline[1].p99_ns);
    EXPECT_EQ(b->warnings, a->warnings);
}

// Issue #31: merge decoded every line of every log before adding any (a 270 KB histogram per
// line: a 366 KB log took 2.6 GB, an 8-hour soak 23 GB). Two 20-minute logs of 3,600 lines
// each (1.9 GB once decoded) merge now in a child limited to 512 MB of address space.
TEST(Merge, LongLogsMergeStreamedInBoundedMemory) {
    constexpr int kIntervals = 1200;
    constexpr std::uint64_t kPerInterval = 100;
    std::mt19937_64 rng(5);
    stats::Histogram unused, unused_read;
    std::vector<ShardRun> runs;
    for (const char* id : {"long-a", "long-b"}) {
        ShardRun s = make_shard(id, 1000.0, 0, rng, unused, unused_read);
        s.summary.metadata.requested_duration_ns = kIntervals * kSecond;
        s.summary.metadata.measured_duration_ns = kIntervals * kSecond;
        s.latency_count = kIntervals * kPerInterval;
        s.hlog_path = (std::filesystem::temp_directory_path() /
                       ("merge-long-" + std::to_string(::getpid()) + s.hlog_path))
                          .string();
        s.log_from_file = true;
        HlogWriter writer;
        ASSERT_TRUE(writer.open(s.hlog_path, "mbstorm interval log: test t, run x").ok());
        writer.start(std::chrono::system_clock::time_point{});
        stats::Histogram all, read;
        for (int k = 0; k < kIntervals; ++k) {
            all.reset();
            read.reset();
            for (std::uint64_t i = 0; i < kPerInterval; ++i) {
                const std::uint64_t v = 1000 + rng() % 5'000'000;
                all.record(v);
                read.record(v);
            }
            writer.write_interval("", k, 1.0, all);
            writer.write_interval("read", k, 1.0, read);
            writer.write_interval("write", k, 1.0, stats::Histogram());
            stats::IntervalSummary iv;
            iv.index = static_cast<std::uint64_t>(k);
            iv.start_offset_ns = k * kSecond;
            iv.transactions = kPerInterval;
            s.summary.timeline.push_back(iv);
        }
        const Error closed = writer.close();
        ASSERT_TRUE(closed.ok()) << closed.text();
        runs.push_back(std::move(s));
    }
    auto remove_logs = [&runs] {
        for (const auto& s : runs) std::remove(s.hlog_path.c_str());
    };
    // The child first: merged in the test's own process, a regression would take 1.9 GB.
    if (!kAddressSanitizer && merge_within(runs, 512) != kMergedExit) {
        remove_logs();
        FAIL() << "the merge did not fit in 512 MB";
    }
    const Result<MergeOutcome> r = merge_shards(runs);
    remove_logs();
    ASSERT_TRUE(r.ok()) << r.error().text();
    EXPECT_TRUE(r->warnings.empty()) << r->warnings.front();
    EXPECT_EQ(r->run.latency.total_count(), 2 * kIntervals * kPerInterval);
    EXPECT_EQ(r->run.operations[0].latency.total_count(), 2 * kIntervals * kPerInterval);
    ASSERT_EQ(r->run.timeline.size(), static_cast<std::size_t>(kIntervals));
    EXPECT_EQ(r->run.timeline[kIntervals - 1].latency_count, 2 * kPerInterval);
}

// Numbers a run never writes (found by editing one field of a real summary): each refused
// naming the field, never converted out of range or allocated for.
TEST(Merge, RefusesTimesIntervalsAndShardCountsNoRunWrites) {
    std::ifstream in(std::string(MBSTORM_SOURCE_DIR) + "/fuzz/corpus/merge_json/1.json");
    const nlohmann::json real = nlohmann::json::parse(in);
    const std::string path = (std::filesystem::temp_directory_path() /
                              ("merge-bounds-" + std::to_string(::getpid()) + ".json"))
                                 .string();
    auto error_with = [&](const nlohmann::json::json_pointer& field, const nlohmann::json& value) {
        nlohmann::json doc = real;
        doc[field] = value;
        std::ofstream(path) << doc.dump();
        ShardRun run;
        const Error error = read_shard_summary(path, run);
        std::remove(path.c_str());
        return error.ok() ? std::string("read") : error.message();
    };
    using ptr = nlohmann::json::json_pointer;
    EXPECT_EQ(error_with(ptr("/timeline/interval_s"), 1.0), "read");
    EXPECT_NE(error_with(ptr("/timeline/interval_s"), 1e-6)
                  .find("interval_s is 1e-06: not a number from 0.001"),
              std::string::npos);
    EXPECT_NE(
        error_with(ptr("/run/measured_duration_s"), 1e300).find("measured_duration_s is 1e+300"),
        std::string::npos);
    EXPECT_NE(
        error_with(ptr("/run/requested_duration_s"), -5.0).find("requested_duration_s is -5.0"),
        std::string::npos);
    EXPECT_NE(error_with(ptr("/test/measure_start_epoch_s"), 1e300).find("measure_start_epoch_s"),
              std::string::npos);
    EXPECT_NE(error_with(ptr("/test/shard_count"), 2'000'000'000)
                  .find("shard_count 2000000000 is not one run --shard makes"),
              std::string::npos);
}

}  // namespace mbstorm::report
