// run --timeline: one JSON object per interval, a line each, flushed as it is written.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "report/timeline_stream.hpp"

namespace mbstorm::report {
namespace {

stats::IntervalSummary interval(std::uint64_t index) {
    stats::IntervalSummary i;
    i.index = index;
    i.start_offset_ns = index * 1'000'000'000ULL;
    i.duration_ns = 1'000'000'000ULL;
    i.transactions = 100 + index;
    i.errors = 2;
    i.latency_count = 98;
    i.p50_ns = 1000;
    i.p99_ns = 5000;
    i.max_ns = 9000;
    i.target_rate = 100;
    i.open_connections = 4;
    return i;
}

std::string read_file(const std::string& path) {
    std::ifstream in(path);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

TEST(TimelineStream, OneLineOfJsonPerIntervalWithTheTimelinesKeys) {
    const auto start = std::chrono::system_clock::time_point(std::chrono::seconds(1'800'000'000));
    const std::string line = format_timeline_line(interval(3), start, "soak", "abcd");
    ASSERT_FALSE(line.empty());
    EXPECT_EQ(line.back(), '\n');
    EXPECT_EQ(line.find('\n'), line.size() - 1);
    const auto j = nlohmann::json::parse(line);
    EXPECT_EQ(j["index"], 3);
    EXPECT_EQ(j["transactions"], 103);
    EXPECT_EQ(j["errors"], 2);
    EXPECT_EQ(j["latency_count"], 98);
    EXPECT_DOUBLE_EQ(j["start_offset_s"].get<double>(), 3.0);
    EXPECT_DOUBLE_EQ(j["duration_s"].get<double>(), 1.0);
    EXPECT_DOUBLE_EQ(j["epoch_s"].get<double>(), 1'800'000'003.0);
    EXPECT_DOUBLE_EQ(j["throughput_per_s"].get<double>(), 103.0);
    EXPECT_EQ(j["p99_ns"], 5000);
    EXPECT_EQ(j["open_connections"], 4);
    EXPECT_EQ(j["test"], "soak");
    EXPECT_EQ(j["run_id"], "abcd");
    for (const char* key :
         {"p50_ns", "p90_ns", "p99_9_ns", "max_ns", "mean_ns", "target_rate_per_s"})
        EXPECT_TRUE(j.contains(key)) << key;
}

TEST(TimelineStream, EachIntervalIsOnDiskOnceWritten) {
    const std::string path = ::testing::TempDir() + "timeline_stream_test.jsonl";
    TimelineWriter writer;
    const Error opened = writer.open(path, "t", "r");
    ASSERT_TRUE(opened.ok()) << opened.text();
    const auto start = std::chrono::system_clock::now();
    writer.write(interval(0), start);
    // Flushed: another reader sees the line while the writer is still open.
    const std::string one = read_file(path);
    EXPECT_EQ(std::count(one.begin(), one.end(), '\n'), 1);
    writer.write(interval(1), start);
    const std::string both = read_file(path);
    EXPECT_EQ(std::count(both.begin(), both.end(), '\n'), 2);
    const Error closed = writer.close();
    ASSERT_TRUE(closed.ok()) << closed.text();
    std::remove(path.c_str());
}

TEST(TimelineStream, AnUnwritablePathIsAnError) {
    TimelineWriter writer;
    const Error error = writer.open("/nonexistent-dir/x.jsonl", "", "");
    EXPECT_EQ(error.code(), ErrorCode::Io);
    EXPECT_EQ(error.text(), "/nonexistent-dir/x.jsonl: No such file or directory");
}

}  // namespace
}  // namespace mbstorm::report
