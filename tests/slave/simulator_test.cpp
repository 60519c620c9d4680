// Simulated inputs: waveform values at given times and what update() writes.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>

#include "slave/device_yaml.hpp"
#include "slave/simulator.hpp"

namespace mbstorm::slave {
namespace {

constexpr std::uint64_t kMs = 1'000'000;

SimulatedInput wave(Waveform w, double amplitude, double offset, std::uint64_t period_ms = 1000) {
    SimulatedInput s;
    s.wave = w;
    s.amplitude = amplitude;
    s.offset = offset;
    s.period_ns = period_ms * kMs;
    return s;
}

TEST(Simulator, SineValues) {
    const SimulatedInput s = wave(Waveform::Sine, 1000, 2000);
    EXPECT_NEAR(simulated_value(s, 0), 2000, 1e-9);
    EXPECT_NEAR(simulated_value(s, 250 * kMs), 3000, 1e-9);
    EXPECT_NEAR(simulated_value(s, 500 * kMs), 2000, 1e-9);
    EXPECT_NEAR(simulated_value(s, 750 * kMs), 1000, 1e-9);
    EXPECT_NEAR(simulated_value(s, 1250 * kMs), 3000, 1e-9);  // periodic
    SimulatedInput shifted = s;
    shifted.phase = 0.25;
    EXPECT_NEAR(simulated_value(shifted, 0), 3000, 1e-9);
}

TEST(Simulator, RampAndSquareValues) {
    const SimulatedInput ramp = wave(Waveform::Ramp, 100, 10);
    EXPECT_DOUBLE_EQ(simulated_value(ramp, 0), 10);
    EXPECT_DOUBLE_EQ(simulated_value(ramp, 500 * kMs), 60);
    EXPECT_NEAR(simulated_value(ramp, 999 * kMs), 109.9, 1e-9);
    EXPECT_DOUBLE_EQ(simulated_value(ramp, 1000 * kMs), 10);
    SimulatedInput sq = wave(Waveform::Square, 5, 1);
    sq.duty = 0.25;
    EXPECT_DOUBLE_EQ(simulated_value(sq, 0), 6);
    EXPECT_DOUBLE_EQ(simulated_value(sq, 249 * kMs), 6);
    EXPECT_DOUBLE_EQ(simulated_value(sq, 250 * kMs), 1);
    EXPECT_DOUBLE_EQ(simulated_value(sq, 1100 * kMs), 6);
}

TEST(Simulator, RandomChangesOncePerPeriodAndStaysInRange) {
    SimulatedInput r = wave(Waveform::Random, 0, 0, 100);
    r.min = 5;
    r.max = 9;
    r.seed = 11;
    EXPECT_EQ(simulated_value(r, 10 * kMs), simulated_value(r, 90 * kMs));
    int changes = 0;
    for (std::uint64_t k = 0; k < 200; ++k) {
        const double v = simulated_value(r, k * 100 * kMs);
        ASSERT_GE(v, 5);
        ASSERT_LE(v, 9);
        ASSERT_EQ(v, std::floor(v));
        changes += v != simulated_value(r, (k + 1) * 100 * kMs);
    }
    EXPECT_GT(changes, 100);
}

TEST(Simulator, EncodeValueRoundsClampsAndSplitsFloats) {
    std::uint16_t r[2] = {};
    encode_value(12.6, ValueType::UInt16, r);
    EXPECT_EQ(r[0], 13);
    encode_value(-5, ValueType::UInt16, r);
    EXPECT_EQ(r[0], 0);
    encode_value(1e9, ValueType::UInt16, r);
    EXPECT_EQ(r[0], 65535);
    encode_value(-2, ValueType::Int16, r);
    EXPECT_EQ(r[0], 0xFFFE);
    encode_value(-1e9, ValueType::Int16, r);
    EXPECT_EQ(r[0], 0x8000);
    encode_value(1.0, ValueType::Float32, r);
    EXPECT_EQ(r[0], 0x3F80);
    EXPECT_EQ(r[1], 0x0000);
}

TEST(Simulator, UpdateWritesRegistersBitsAndCounters) {
    const DeviceDescription d = *parse_device_yaml(R"(
simulate:
  - {table: input_registers, address: 10, wave: sine, period_ms: 1000, amplitude: 100, offset: 500}
  - {table: holding_registers, address: 20, wave: ramp, period_ms: 1000, amplitude: 1000, type: float32}
  - {table: discrete_inputs, address: 3, wave: square, period_ms: 1000, amplitude: 1}
counters:
  - {table: input_registers, address: 30, mode: interval, interval_ms: 100, step: 1000, start: 65000}
)");
    const UnitModels units = build_units(d);
    Simulator sim(d.simulated, units);
    DataModel& m = units.model_at(0);

    sim.update(250 * kMs);
    EXPECT_EQ(m.input_registers().get(10), 600);
    const auto ramp = std::bit_cast<float>((std::uint32_t{m.holding_registers().get(20)} << 16) |
                                           m.holding_registers().get(21));
    EXPECT_FLOAT_EQ(ramp, 250.0f);
    EXPECT_TRUE(m.discrete_inputs().get(3));
    EXPECT_EQ(m.input_registers().get(30), static_cast<std::uint16_t>(65000 + 2 * 1000));  // wraps

    sim.update(750 * kMs);
    EXPECT_EQ(m.input_registers().get(10), 400);
    EXPECT_FALSE(m.discrete_inputs().get(3));
    EXPECT_EQ(m.input_registers().get(30), static_cast<std::uint16_t>(65000 + 7 * 1000));
}

TEST(Simulator, PerUnitTargets) {
    const DeviceDescription d = *parse_device_yaml(R"(
units: [1, 2]
simulate:
  - {table: input_registers, address: 0, wave: square, period_ms: 1000, amplitude: 9, units: [2]}
)");
    const UnitModels units = build_units(d);
    Simulator sim(d.simulated, units);
    sim.update(0);
    EXPECT_EQ(units.find(1)->input_registers().get(0), 0);
    EXPECT_EQ(units.find(2)->input_registers().get(0), 9);
}

}  // namespace
}  // namespace mbstorm::slave
