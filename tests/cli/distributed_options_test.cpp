// run --shard I/N (or the Indexed Job's environment) and --start-at TIME.
#include "cli/distributed_options.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "../support/run_mbstorm.hpp"

namespace mbstorm::cli {
namespace {

using testing::HasSubstr;
using Clock = std::chrono::system_clock;

// Exact (a double of epoch nanoseconds is not).
Clock::time_point at_epoch(std::int64_t seconds, std::int64_t nanos = 0) {
    return Clock::time_point(std::chrono::duration_cast<Clock::duration>(
        std::chrono::seconds(seconds) + std::chrono::nanoseconds(nanos)));
}

TEST(Shard, FromTheFlagOrTheEnvironmentAndTheFlagWins) {
    load::Plan::Shard s;
    EXPECT_EQ(resolve_shard("1/3", nullptr, nullptr, s).text(), "");
    EXPECT_EQ(s.index, 1u);
    EXPECT_EQ(s.count, 3u);
    EXPECT_EQ(resolve_shard("", "2", "4", s).text(), "");
    EXPECT_EQ(s.index, 2u);
    EXPECT_EQ(s.count, 4u);
    EXPECT_EQ(resolve_shard("0/2", "2", "4", s).text(), "");
    EXPECT_EQ(s.index, 0u);
    EXPECT_EQ(s.count, 2u);
    // Not sharded: no count anywhere (an Indexed Job's index alone is not ours).
    EXPECT_EQ(resolve_shard("", "5", nullptr, s).text(), "");
    EXPECT_EQ(s.count, 0u);
    EXPECT_EQ(resolve_shard("", nullptr, "", s).text(), "");
    EXPECT_EQ(s.count, 0u);
}

TEST(Shard, BadValuesSayWhereTheyCameFrom) {
    load::Plan::Shard s;
    EXPECT_EQ(resolve_shard("3/3", nullptr, nullptr, s).text(),
              "--shard '3/3': index 3 is out of range for 3 shards (valid 0..2: shards count "
              "from 0)");
    EXPECT_EQ(resolve_shard("1-3", nullptr, nullptr, s).text(),
              "--shard '1-3': expected I/N, e.g. 0/3 (shard I of N, from 0)");
    EXPECT_EQ(resolve_shard("-1/3", nullptr, nullptr, s).text(),
              "--shard '-1/3': expected I/N, e.g. 0/3 (shard I of N, from 0)");
    EXPECT_EQ(resolve_shard("0/0", nullptr, nullptr, s).text(),
              "--shard '0/0': shard count 0 is out of range (valid 1..100000)");
    EXPECT_EQ(resolve_shard("", nullptr, "3", s).text(),
              "MBSTORM_SHARD_COUNT=3 is set but JOB_COMPLETION_INDEX is not (run as a Kubernetes "
              "Indexed Job, or give --shard I/N)");
    EXPECT_EQ(resolve_shard("", "x", "3", s).text(),
              "JOB_COMPLETION_INDEX='x': expected the shard index, a whole number");
    EXPECT_EQ(resolve_shard("", "1", "three", s).text(),
              "MBSTORM_SHARD_COUNT='three': expected the shard count, a whole number");
    EXPECT_EQ(resolve_shard("", "7", "3", s).text(),
              "JOB_COMPLETION_INDEX=7, MBSTORM_SHARD_COUNT=3: index 7 is out of range for 3 "
              "shards (valid 0..2: shards count from 0)");
    EXPECT_EQ(s.count, 0u);
}

TEST(StartAt, Rfc3339WithZOrAnOffsetAndEpochSeconds) {
    const Clock::time_point now = at_epoch(1795528000);  // 2026-11-24T13:46:40Z
    Clock::time_point t;
    EXPECT_EQ(parse_start_at("2026-11-24T14:00:00Z", now, t).text(), "");
    EXPECT_EQ(t, at_epoch(1795528800));
    EXPECT_EQ(parse_start_at("2026-11-24t14:00:00.25z", now, t).text(), "");
    EXPECT_EQ(t, at_epoch(1795528800, 250'000'000));
    EXPECT_EQ(parse_start_at("2026-11-24T15:30:00+01:30", now, t).text(), "");
    EXPECT_EQ(t, at_epoch(1795528800));
    EXPECT_EQ(parse_start_at("2026-11-24T09:00:00-05:00", now, t).text(), "");
    EXPECT_EQ(t, at_epoch(1795528800));
    EXPECT_EQ(parse_start_at("1795528800", now, t).text(), "");
    EXPECT_EQ(t, at_epoch(1795528800));
    EXPECT_EQ(parse_start_at("1795528800.5", now, t).text(), "");
    EXPECT_EQ(t, at_epoch(1795528800, 500'000'000));
    // In the past is fine (a late shard starts at once), within a day.
    EXPECT_EQ(parse_start_at("2026-11-24T13:00:00Z", now, t).text(), "");
}

TEST(StartAt, MalformedOrFarTimesAreRefused) {
    const Clock::time_point now = at_epoch(1795528000);
    Clock::time_point t;
    EXPECT_THAT(parse_start_at("2026-11-24T14:00:00", now, t).text(),
                HasSubstr("no time zone: end it with Z (UTC) or an offset like +01:00"));
    EXPECT_THAT(parse_start_at("2026-11-24 14:00", now, t).text(),
                HasSubstr("not of the form 2026-11-24T14:00:00Z"));
    EXPECT_THAT(parse_start_at("2026-02-30T14:00:00Z", now, t).text(),
                HasSubstr("no such date or time of day"));
    EXPECT_THAT(parse_start_at("2026-11-24T14:00:00+1", now, t).text(),
                HasSubstr("a UTC offset must be +HH:MM or -HH:MM"));
    EXPECT_THAT(parse_start_at("soon", now, t).text(), HasSubstr("not seconds since the epoch"));
    EXPECT_THAT(parse_start_at("12.", now, t).text(), HasSubstr("not seconds since the epoch"));
    EXPECT_EQ(parse_start_at("2026-11-26T14:00:00Z", now, t).text(),
              "--start-at '2026-11-26T14:00:00Z' is 48.2 h ahead (at most 24 h either way: check "
              "the time and this machine's clock)");
    EXPECT_THAT(parse_start_at("0", now, t).text(), HasSubstr("h ago (at most 24 h either way"));
}

TEST(ShardRun, ABadShardIsAUsageErrorBeforeAnythingRuns) {
    auto r = test::run_mbstorm("run -c 2 -d 1s -q --shard 2/3", 30);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_THAT(r.output, HasSubstr("shard 2/3 gets 0 of the plan's 2 connections"));
    r = test::run_mbstorm("run -c 2 -d 1s -q --start-at yesterday", 30);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_THAT(r.output, HasSubstr("--start-at 'yesterday'"));
}

}  // namespace
}  // namespace mbstorm::cli
