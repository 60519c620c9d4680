// The staged schedule as a function of time, and the pacer's live rate changes it drives.
#include <gtest/gtest.h>

#include "load/pacer.hpp"
#include "load/stage_schedule.hpp"

namespace mbstorm::load {
namespace {

using namespace std::chrono_literals;
constexpr std::int64_t kSecond = 1'000'000'000;

Stage stage(Duration d, std::optional<double> rate, std::optional<std::uint32_t> connections,
            Ramp ramp = Ramp::Linear) {
    Stage s;
    s.duration = d;
    s.target_rate = rate;
    s.target_connections = connections;
    s.ramp = ramp;
    return s;
}

TEST(StageSchedule, LinearRampsStartFromThePreviousValues) {
    Plan plan;
    plan.model = LoadModel::OpenLoop;
    plan.rate = 100;
    plan.connections = 4;
    plan.stages = {stage(2s, 1100, std::nullopt), stage(1s, std::nullopt, 8, Ramp::Constant),
                   stage(1s, 0, 0)};
    const StageSchedule s(plan);
    EXPECT_EQ(s.total_ns(), 4 * kSecond);
    EXPECT_DOUBLE_EQ(s.at(-1).rate, 100);  // warm-up: the first stage's start
    EXPECT_DOUBLE_EQ(s.at(0).rate, 100);
    EXPECT_DOUBLE_EQ(s.at(kSecond / 2).rate, 350);
    EXPECT_DOUBLE_EQ(s.at(kSecond).rate, 600);
    EXPECT_EQ(s.at(kSecond).connections, 4U);
    EXPECT_EQ(s.at(kSecond).stage, 0U);
    // A constant stage jumps to its values and keeps the rate it does not name.
    EXPECT_EQ(s.at(2 * kSecond).stage, 1U);
    EXPECT_EQ(s.at(2 * kSecond).connections, 8U);
    EXPECT_DOUBLE_EQ(s.at(2 * kSecond + 1).rate, 1100);
    // Ramp down to nothing.
    EXPECT_DOUBLE_EQ(s.at(3 * kSecond + kSecond / 2).rate, 550);
    EXPECT_EQ(s.at(3 * kSecond + kSecond / 2).connections, 4U);
    EXPECT_DOUBLE_EQ(s.at(10 * kSecond).rate, 0);
    EXPECT_EQ(s.at(10 * kSecond).connections, 0U);
    EXPECT_EQ(s.stage_at(10 * kSecond), 2U);
    EXPECT_EQ(s.peak_connections(), 8U);
    EXPECT_DOUBLE_EQ(s.peak_rate(), 1100);
    EXPECT_EQ(s.stage_start_ns(1), 2 * kSecond);
    EXPECT_EQ(s.stage_end_ns(1), 3 * kSecond);
}

TEST(StageSchedule, ConnectionRampsRoundToWholeConnections) {
    Plan plan;
    plan.connections = 1;
    plan.stages = {stage(1s, std::nullopt, 11)};
    const StageSchedule s(plan);
    EXPECT_EQ(s.at(0).connections, 1U);
    EXPECT_EQ(s.at(200'000'000).connections, 3U);  // 1 + 10 * 0.2
    EXPECT_EQ(s.at(640'000'000).connections, 7U);  // 7.4 rounds down
    EXPECT_EQ(s.at(kSecond).connections, 11U);
    EXPECT_DOUBLE_EQ(s.at(0).rate, 0);  // closed loop: no rate
    EXPECT_EQ(peak_connections(plan), 11U);
}

TEST(StageSchedule, NoStagesMeansThePlanValues) {
    Plan plan;
    plan.connections = 7;
    const StageSchedule s(plan);
    EXPECT_TRUE(s.empty());
    EXPECT_EQ(s.at(123).connections, 7U);
    EXPECT_EQ(s.total_ns(), 0);
}

TEST(Pacer, ZeroRatePausesAndAPositiveRateResumesNow) {
    Pacer pacer(0.0, Arrival::Even, 1, 0);
    EXPECT_FALSE(pacer.due(10 * kSecond));
    pacer.set_rate(1000.0, 5 * kSecond);
    EXPECT_EQ(pacer.next_intended_ns(), 5 * kSecond);
    pacer.advance();
    EXPECT_EQ(pacer.next_intended_ns(), 5 * kSecond + 1'000'000);
    pacer.set_rate(0.0, 5 * kSecond + 500'000);
    EXPECT_TRUE(pacer.paused());
    EXPECT_FALSE(pacer.due(100 * kSecond));
}

TEST(Pacer, RaisingTheRateBringsTheNextSendCloserButNeverForgivesABacklog) {
    Pacer pacer(10.0, Arrival::Even, 1, 0);  // one send every 100 ms
    pacer.advance();                         // next at 100 ms
    pacer.set_rate(1000.0, 10'000'000);      // at 10 ms: next within 1 ms
    EXPECT_EQ(pacer.next_intended_ns(), 11'000'000);
    // Behind schedule: the overdue slot stays where it was.
    Pacer late(1000.0, Arrival::Even, 1, 0);
    late.set_rate(2000.0, 50'000'000);
    EXPECT_EQ(late.next_intended_ns(), 0);
}

}  // namespace
}  // namespace mbstorm::load
