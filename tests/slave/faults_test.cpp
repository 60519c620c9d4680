// Fault policy: validation, decision rates for a fixed seed, delays, stalls.
#include <gtest/gtest.h>

#include <cmath>

#include "slave/faults.hpp"

namespace mbstorm::slave {
namespace {

using Action = FaultDecision::Action;

TEST(Faults, OffByDefault) {
    FaultConfig c;
    EXPECT_FALSE(c.any());
    EXPECT_TRUE(validate(c).ok());
    FaultInjector inj(c);
    EXPECT_FALSE(inj.enabled());
    for (int i = 0; i < 1000; ++i) {
        const FaultDecision d = inj.decide();
        EXPECT_EQ(d.action, Action::Answer);
        EXPECT_EQ(d.delay_ns, 0u);
    }
    EXPECT_EQ(inj.held_until(123456789), 123456789u);
}

TEST(Faults, ValidationNamesTheProblem) {
    FaultConfig c;
    c.exception_rate = 1.5;
    EXPECT_NE(validate(c).message().find("exception rate"), std::string::npos);
    c = {};
    c.drop_rate = 0.6;
    c.no_answer_rate = 0.6;
    EXPECT_NE(validate(c).message().find("add up"), std::string::npos);
    c = {};
    c.delay.kind = DelayConfig::Kind::Uniform;
    c.delay.min_ns = 10;
    c.delay.max_ns = 5;
    EXPECT_NE(validate(c).message().find("min <= max"), std::string::npos);
    c = {};
    c.stall = {2'000, 1'000};
    EXPECT_NE(validate(c).message().find("stall"), std::string::npos);
    c = {};
    c.exception_rate = 0.1;
    c.exception_code = codec::ExceptionCode::None;
    EXPECT_NE(validate(c).message().find("code"), std::string::npos);
    c = {};
    c.drop_rate = std::nan("");
    EXPECT_EQ(validate(c).code(), ErrorCode::InvalidInput);
}

TEST(Faults, RatesMatchForAFixedSeed) {
    FaultConfig c;
    c.drop_rate = 0.01;
    c.no_answer_rate = 0.05;
    c.exception_rate = 0.10;
    c.exception_code = codec::ExceptionCode::ServerDeviceBusy;
    c.seed = 12345;
    ASSERT_TRUE(validate(c).ok());
    FaultInjector inj(c, 0);
    constexpr int kDraws = 200'000;
    int drops = 0, silent = 0, exceptions = 0, answers = 0;
    for (int i = 0; i < kDraws; ++i) {
        const FaultDecision d = inj.decide();
        switch (d.action) {
            case Action::Drop:
                ++drops;
                break;
            case Action::NoAnswer:
                ++silent;
                break;
            case Action::Exception:
                ++exceptions;
                EXPECT_EQ(d.exception, codec::ExceptionCode::ServerDeviceBusy);
                break;
            case Action::Answer:
                ++answers;
                break;
        }
    }
    // Binomial standard deviations are at most ~0.07% of kDraws here; allow about 5 sigma.
    EXPECT_NEAR(drops / double(kDraws), 0.01, 0.002);
    EXPECT_NEAR(silent / double(kDraws), 0.05, 0.003);
    EXPECT_NEAR(exceptions / double(kDraws), 0.10, 0.004);
    EXPECT_NEAR(answers / double(kDraws), 0.84, 0.005);
}

TEST(Faults, SameSeedSameStreamIsReproducibleOtherStreamsDiffer) {
    FaultConfig c;
    c.exception_rate = 0.5;
    c.seed = 7;
    FaultInjector a(c, 3), b(c, 3), other(c, 4);
    int same = 0, differ = 0;
    for (int i = 0; i < 1000; ++i) {
        const auto x = a.decide().action, y = b.decide().action, z = other.decide().action;
        same += x == y;
        differ += x != z;
    }
    EXPECT_EQ(same, 1000);
    EXPECT_GT(differ, 300);
}

TEST(Faults, RateOneAlwaysFires) {
    FaultConfig c;
    c.no_answer_rate = 1.0;
    FaultInjector inj(c);
    for (int i = 0; i < 1000; ++i) EXPECT_EQ(inj.decide().action, Action::NoAnswer);
}

TEST(Faults, FixedAndUniformDelays) {
    FaultConfig c;
    c.delay.kind = DelayConfig::Kind::Fixed;
    c.delay.fixed_ns = 5'000'000;
    FaultInjector fixed(c);
    EXPECT_EQ(fixed.decide().delay_ns, 5'000'000u);

    c.delay.kind = DelayConfig::Kind::Uniform;
    c.delay.min_ns = 1'000;
    c.delay.max_ns = 2'000;
    FaultInjector uni(c);
    double sum = 0;
    std::uint64_t lo = UINT64_MAX, hi = 0;
    for (int i = 0; i < 100'000; ++i) {
        const std::uint64_t d = uni.decide().delay_ns;
        lo = std::min(lo, d);
        hi = std::max(hi, d);
        sum += static_cast<double>(d);
    }
    EXPECT_GE(lo, 1'000u);
    EXPECT_LE(hi, 2'000u);
    EXPECT_LT(lo, 1'010u);
    EXPECT_GT(hi, 1'990u);
    EXPECT_NEAR(sum / 100'000, 1'500.0, 10.0);
}

TEST(Faults, ExponentialDelayHasTheConfiguredMean) {
    FaultConfig c;
    c.delay.kind = DelayConfig::Kind::Exponential;
    c.delay.mean_ns = 1'000'000;
    c.seed = 99;
    FaultInjector inj(c);
    constexpr int kDraws = 200'000;
    double sum = 0;
    int above_mean = 0;
    for (int i = 0; i < kDraws; ++i) {
        const double d = static_cast<double>(inj.decide().delay_ns);
        sum += d;
        above_mean += d > 1'000'000;
    }
    EXPECT_NEAR(sum / kDraws, 1'000'000.0, 15'000.0);                 // sd of the mean is ~2'200
    EXPECT_NEAR(above_mean / double(kDraws), std::exp(-1.0), 0.005);  // P(X > mean) = 1/e
}

TEST(Faults, DelaysApplyToInjectedExceptionsButNotToDrops) {
    FaultConfig c;
    c.delay.kind = DelayConfig::Kind::Fixed;
    c.delay.fixed_ns = 777;
    c.exception_rate = 0.5;
    c.drop_rate = 0.5;
    FaultInjector inj(c);
    for (int i = 0; i < 1000; ++i) {
        const FaultDecision d = inj.decide();
        EXPECT_EQ(d.delay_ns, d.action == Action::Exception ? 777u : 0u);
    }
}

TEST(Faults, StallHoldsResponsesAtTheStartOfEachPeriod) {
    FaultConfig c;
    c.stall.duration_ns = 100;
    c.stall.period_ns = 1'000;
    const std::uint64_t origin = 50'000;
    FaultInjector inj(c, 0, origin);
    EXPECT_EQ(inj.held_until(origin + 10), origin + 10);  // no stall in the first period
    EXPECT_EQ(inj.held_until(origin + 999), origin + 999);
    EXPECT_EQ(inj.held_until(origin + 1'000), origin + 1'100);  // stall begins
    EXPECT_EQ(inj.held_until(origin + 1'099), origin + 1'100);
    EXPECT_EQ(inj.held_until(origin + 1'100), origin + 1'100);  // over
    EXPECT_EQ(inj.held_until(origin + 5'042), origin + 5'100);
    EXPECT_EQ(inj.held_until(origin + 5'500), origin + 5'500);
    EXPECT_EQ(inj.held_until(10), 10u);  // before the origin
}

TEST(Faults, RngBetweenCoversTheRangeInclusive) {
    FastRng rng(1);
    bool seen[4] = {};
    for (int i = 0; i < 1000; ++i) {
        const auto v = rng.between(10, 13);
        ASSERT_GE(v, 10u);
        ASSERT_LE(v, 13u);
        seen[v - 10] = true;
    }
    EXPECT_TRUE(seen[0] && seen[1] && seen[2] && seen[3]);
    EXPECT_EQ(rng.between(5, 5), 5u);
}

}  // namespace
}  // namespace mbstorm::slave
