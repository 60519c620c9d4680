#include "load/pacer.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace mbstorm::load {
namespace {

TEST(Pacer, EvenScheduleIsExactlySpaced) {
    Pacer pacer(1000.0, Arrival::Even, 1, 5'000'000);  // 1 ms apart
    for (int k = 0; k < 10000; ++k) {
        ASSERT_EQ(pacer.next_intended_ns(), 5'000'000 + k * 1'000'000LL);
        pacer.advance();
    }
    EXPECT_EQ(pacer.scheduled(), 10000u);
}

TEST(Pacer, EvenScheduleDoesNotDriftWithFractionalPeriods) {
    Pacer pacer(3.0, Arrival::Even, 1, 0);  // 333333333.33 ns apart
    for (int k = 0; k < 300000; ++k) pacer.advance();
    EXPECT_NEAR(static_cast<double>(pacer.next_intended_ns()), 100000e9, 1.0);
}

TEST(Pacer, DueFollowsTheClock) {
    Pacer pacer(100.0, Arrival::Even, 1, 1000);
    EXPECT_FALSE(pacer.due(999));
    EXPECT_TRUE(pacer.due(1000));
    pacer.advance();
    EXPECT_FALSE(pacer.due(1000 + 9'999'999));
    EXPECT_TRUE(pacer.due(1000 + 10'000'000));
}

TEST(Pacer, PoissonHasTheMeanRateAndExponentialGaps) {
    Pacer pacer(50000.0, Arrival::Poisson, 9, 0);  // mean gap 20 us
    constexpr int kCount = 200000;
    std::int64_t previous = 0;
    double sum = 0, sum_sq = 0;
    for (int k = 0; k < kCount; ++k) {
        const double gap = static_cast<double>(pacer.next_intended_ns() - previous);
        ASSERT_GE(gap, 0);
        sum += gap;
        sum_sq += gap * gap;
        previous = pacer.next_intended_ns();
        pacer.advance();
    }
    const double mean = sum / kCount;
    const double stddev = std::sqrt(sum_sq / kCount - mean * mean);
    EXPECT_NEAR(mean, 20000.0, 20000.0 * 0.01);
    // An exponential distribution's standard deviation equals its mean.
    EXPECT_NEAR(stddev, 20000.0, 20000.0 * 0.03);
}

TEST(Pacer, SetRateKeepsTheScheduleContinuous) {
    Pacer pacer(1000.0, Arrival::Even, 1, 0);
    for (int k = 0; k < 10; ++k) pacer.advance();
    pacer.set_rate(2000.0, 10'000'000);
    EXPECT_EQ(pacer.next_intended_ns(), 10'000'000);
    pacer.advance();
    EXPECT_EQ(pacer.next_intended_ns(), 10'500'000);
}

TEST(LagTracker, CountsOnlySendsLaterThanTheThreshold) {
    LagTracker lag(1'000'000);
    lag.record(0, 500'000);
    lag.record(0, 1'000'000);
    EXPECT_EQ(lag.late_sends(), 0u);
    lag.record(10, 3'000'010);
    lag.record(0, 2'000'000);
    EXPECT_EQ(lag.late_sends(), 2u);
    EXPECT_EQ(lag.max_lag_ns(), 3'000'000u);
    EXPECT_EQ(lag.total_lag_ns(), 5'000'000u);
}

// Late sends after the schedule found every window full are the target's; the first send on
// time clears that, and later late sends are the engine's again.
TEST(LagTracker, BlamesTheTargetOnlyWhileSendsWaitedForAFreeWindow) {
    LagTracker lag(1'000'000);
    lag.record(0, 5'000'000);
    EXPECT_EQ(lag.lag().engine.late_sends, 1u);
    lag.note_window_full();
    lag.record(0, 7'000'000);
    lag.record(0, 9'000'000);
    EXPECT_EQ(lag.lag().target.late_sends, 2u);
    EXPECT_EQ(lag.lag().target.max_lag_ns, 9'000'000u);
    lag.record(0, 500'000);  // on time: the window had room again
    lag.record(0, 4'000'000);
    EXPECT_EQ(lag.lag().engine.late_sends, 2u);
    EXPECT_EQ(lag.lag().target.late_sends, 2u);
    EXPECT_EQ(lag.late_sends(), 4u);
    // Warm-up: the cause is tracked, nothing is counted.
    lag.note_window_full();
    lag.record(0, 8'000'000, false);
    EXPECT_EQ(lag.late_sends(), 4u);
}

// An engine that stalled 130 ms at 1,000/s sends its backlog at once when it wakes: 128 sends,
// late by 130 ms down to 3 ms, fill both windows of 64. The sends still due then wait for the
// answers to requests the target has only just been given: as late as the engine made them,
// not the target's. (EngineHonestNumbers.AStalledEngineIsBlamedNotTheTarget failed on this
// when a loaded machine stretched its stalls.) A send later than the engine ever fell behind
// did wait for the target.
TEST(LagTracker, ABacklogThatFillsTheWindowsIsTheEnginesNotTheTargets) {
    constexpr std::int64_t ms = 1'000'000;
    LagTracker lag(ms);
    for (std::int64_t i = 0; i < 128; ++i) lag.record(i * ms, 130 * ms);
    lag.note_window_full();
    lag.record(128 * ms, 132 * ms);  // the first answers came 2 ms after the backlog left
    lag.record(129 * ms, 132 * ms);
    EXPECT_EQ(lag.lag().engine.late_sends, 130u);
    EXPECT_EQ(lag.lag().target.late_sends, 0u);
    // The target stops answering: the next send waits 200 ms, far past the engine's backlog.
    lag.note_window_full();
    lag.record(130 * ms, 330 * ms);
    EXPECT_EQ(lag.lag().target.late_sends, 1u);
    EXPECT_EQ(lag.lag().target.max_lag_ns, static_cast<std::uint64_t>(200 * ms));
    // On time again: the engine's backlog is worked off, and the next window full is the
    // target's from the first late send.
    lag.record(331 * ms, 331 * ms);
    lag.note_window_full();
    lag.record(332 * ms, 335 * ms);
    EXPECT_EQ(lag.lag().target.late_sends, 2u);
    EXPECT_EQ(lag.lag().engine.late_sends, 130u);
}

}  // namespace
}  // namespace mbstorm::load
