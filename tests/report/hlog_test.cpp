#include "report/hlog.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <sstream>

namespace mbstorm::report {
namespace {

std::string temp_path(const char* name) {
    return ::testing::TempDir() + name + std::to_string(::getpid());
}

std::string slurp(const std::string& path) {
    std::ifstream in(path);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

TEST(Hlog, TagsHoldNoSeparators) {
    EXPECT_EQ(hlog_tag("read holding,regs\t1"), "read_holding_regs_1");
    EXPECT_EQ(hlog_tag("read_holding_registers"), "read_holding_registers");
}

TEST(Hlog, IdentityLineNamesTestRunAndShardAndReadsBack) {
    HlogIdentity id{"nightly, 42", "5f0c", 2, 3};
    EXPECT_EQ(hlog_identity_text(id),
              "mbstorm interval log: test nightly, 42, run 5f0c, shard 2/3");
    Hlog log;
    log.comments = {"[some tool]", "[" + hlog_identity_text(id) + "]"};
    HlogIdentity back;
    ASSERT_TRUE(find_hlog_identity(log, back));
    EXPECT_EQ(back.test_id, "nightly, 42");
    EXPECT_EQ(back.run_id, "5f0c");
    EXPECT_EQ(back.shard_index, 2u);
    EXPECT_EQ(back.shard_count, 3u);

    log.comments = {"[" + hlog_identity_text({"", "77", 0, 0}) + "]"};
    EXPECT_EQ(log.comments[0], "[mbstorm interval log: test -, run 77]");
    ASSERT_TRUE(find_hlog_identity(log, back));
    EXPECT_EQ(back.run_id, "77");
    EXPECT_EQ(back.shard_count, 0u);
    log.comments = {"[Histogram log format version 1.3]"};
    EXPECT_FALSE(find_hlog_identity(log, back));
}

TEST(Hlog, WriterWritesHdrHistogramsHeaderAndEveryLineIsFlushedAtOnce) {
    const std::string path = temp_path("hlog_writer");
    HlogWriter writer;
    const Error opened = writer.open(path, "mbstorm interval log: test t, run 01");
    ASSERT_TRUE(opened.ok()) << opened.text();
    // 2026-11-24T08:00:00.250Z
    const auto start =
        std::chrono::system_clock::time_point(std::chrono::milliseconds(1795507200250));
    writer.start(start);
    stats::Histogram all, read;
    all.record(1'500'000);
    all.record(2'000);
    read.record(2'000);
    writer.write_interval("", 0.0, 1.0, all);
    writer.write_interval("read", 0.0, 1.0, read);
    writer.end_interval();
    // Flushed: readable before close, as after a kill.
    const std::string text = slurp(path);
    std::istringstream lines(text);
    std::string line;
    std::getline(lines, line);
    EXPECT_EQ(line, "#[mbstorm interval log: test t, run 01]");
    std::getline(lines, line);
    EXPECT_EQ(line, "#[Histogram log format version 1.3]");
    std::getline(lines, line);
    EXPECT_EQ(line,
              "#[StartTime: 1795507200.250 (seconds since epoch), Tue Nov 24 08:00:00 UTC 2026]");
    std::getline(lines, line);
    EXPECT_EQ(line, "#[BaseTime: 1795507200.250 (seconds since epoch)]");
    std::getline(lines, line);
    EXPECT_EQ(line,
              "\"StartTimestamp\",\"Interval_Length\",\"Interval_Max\",\"Interval_Compressed_"
              "Histogram\"");
    std::getline(lines, line);
    EXPECT_EQ(line.rfind("0.000,1.000,1.500,HISTFAAA", 0), 0u) << line;
    std::getline(lines, line);
    EXPECT_EQ(line.rfind("Tag=read,0.000,1.000,0.002,HISTFAAA", 0), 0u) << line;
    const Error closed = writer.close();
    ASSERT_TRUE(closed.ok()) << closed.text();

    const Result<Hlog> read_back = read_hlog(path);
    ASSERT_TRUE(read_back.ok()) << read_back.error().text();
    const Hlog& log = *read_back;
    std::remove(path.c_str());
    EXPECT_TRUE(log.has_start_time);
    EXPECT_DOUBLE_EQ(log.start_time_s, 1795507200.250);
    ASSERT_EQ(log.intervals.size(), 2u);
    EXPECT_EQ(log.intervals[0].tag, "");
    EXPECT_EQ(log.intervals[0].histogram.total_count(), 2u);
    EXPECT_EQ(log.intervals[1].tag, "read");
    EXPECT_EQ(log.intervals[1].histogram.total_count(), 1u);
    EXPECT_DOUBLE_EQ(log.absolute_start_s(log.intervals[1]), 1795507200.250);
}

TEST(Hlog, ReaderNamesTheBadLine) {
    auto refusal = [](std::string_view text) {
        const Result<Hlog> log = parse_hlog(text);
        EXPECT_EQ(log.error().code(), ErrorCode::InvalidInput);
        return log.error().text();
    };
    EXPECT_EQ(refusal("#[StartTime: 5 (x)]\n0.0,1.0,2.0\n"),
              "line 2: an interval line has four fields: start,length,max,histogram");
    EXPECT_EQ(refusal("0.0,x,2.0,HISTFAAA\n"), "line 1: start, length and max must be numbers");
    EXPECT_EQ(refusal("\n\n0.0,1.0,2.0,AAAA\n"),
              "line 3: not a compressed HdrHistogram V2 encoding");
    const Result<Hlog> missing = read_hlog("/nonexistent/x.hlog");
    EXPECT_EQ(missing.error().code(), ErrorCode::Io);
    EXPECT_EQ(missing.error().text(), "/nonexistent/x.hlog: No such file or directory");
}

// The streaming reader says why it stopped: success at the end of the log, else the bad line.
TEST(Hlog, StreamingReaderStopsAtTheBadLineSayingWhich) {
    std::istringstream good("#[StartTime: 5 (x)]\n");
    HlogReader complete(good);
    HlogInterval interval;
    EXPECT_FALSE(complete.next(interval));
    EXPECT_TRUE(complete.error().ok());
    std::istringstream bad("#[StartTime: 5 (x)]\n0.0,x,2.0,HISTFAAA\n");
    HlogReader broken(bad);
    EXPECT_FALSE(broken.next(interval));
    EXPECT_EQ(broken.error().code(), ErrorCode::InvalidInput);
    EXPECT_EQ(broken.error().text(), "line 2: start, length and max must be numbers");
}

TEST(Hlog, AbsoluteTimesFollowHdrHistogramsRule) {
    // No base time: timestamps far before the start time are relative to it.
    // An empty histogram as HdrHistogram's Java library encodes it.
    const std::string line =
        "2.000,1.000,0.000,HISTFAAAACF4nJNpmSzMwMDAyAABzFAayGd2M9ixgMH+A1QEAFKmBEw=\n";
    const Result<Hlog> parsed = parse_hlog("#[StartTime: 1000000000.000 (x)]\n" + line);
    ASSERT_TRUE(parsed.ok()) << parsed.error().text();
    const Hlog& log = *parsed;
    ASSERT_EQ(log.intervals.size(), 1u);
    EXPECT_DOUBLE_EQ(log.absolute_start_s(log.intervals[0]), 1000000002.0);
}

}  // namespace
}  // namespace mbstorm::report
