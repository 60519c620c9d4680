// Simulated inputs: registers (or bits) whose value is a function of time — ramps, sine and
// square waves, periodic random values and interval counters. The server calls
// Simulator::update() from one thread every 10-100 ms; handlers read the values concurrently.
#pragma once

#include <cstdint>
#include <vector>

#include "slave/data_model.hpp"

namespace mbstorm::slave {

// How a value is stored: one register (uint16 / int16, clamped; counters wrap instead) or two
// registers (float32, IEEE-754, high word first). On a bit table any non-zero value is 1.
enum class ValueType : std::uint8_t { UInt16, Int16, Float32 };

// Registers a value occupies.
constexpr std::uint32_t value_width(ValueType t) noexcept {
    return t == ValueType::Float32 ? 2 : 1;
}

// Writes `v` (rounded to nearest for integer types) as `type` into regs[0..width).
void encode_value(double v, ValueType type, std::uint16_t* regs) noexcept;

enum class Waveform : std::uint8_t {
    Ramp,     // offset + amplitude * phase, phase 0 -> 1 over each period (sawtooth)
    Sine,     // offset + amplitude * sin(2*pi*(t/period + phase_shift))
    Square,   // offset + amplitude for the first `duty` of each period, offset for the rest
    Random,   // a new uniform value in [min, max] every period (deterministic per seed)
    Counter,  // offset + step * floor(t / period), wrapping for integer types
};

struct SimulatedInput {
    Table table = Table::InputRegisters;
    std::uint16_t address = 0;
    ValueType type = ValueType::UInt16;
    Waveform wave = Waveform::Sine;
    std::uint64_t period_ns = 1'000'000'000;
    double amplitude = 0.0;
    double offset = 0.0;
    double phase = 0.0;  // Sine: fraction of a period added to t/period
    double duty = 0.5;   // Square
    double min = 0.0;    // Random
    double max = 0.0;
    double step = 1.0;  // Counter
    std::uint64_t seed = 0;
    std::vector<std::uint8_t> units;  // empty: every model
    bool operator==(const SimulatedInput&) const = default;
};

// The value `input` has `elapsed_ns` after the simulation started (before type conversion).
// Counter values here are not wrapped; encode_value's clamping does not apply to counters,
// which Simulator wraps modulo 2^16 for integer types.
double simulated_value(const SimulatedInput& input, std::uint64_t elapsed_ns) noexcept;

class Simulator {
  public:
    // Precondition: every input fits its table (device_yaml checks this with line numbers).
    Simulator(std::vector<SimulatedInput> inputs, const UnitModels& units);

    bool empty() const noexcept { return inputs_.empty(); }
    // Writes every input's value for `elapsed_ns` since the start into the models.
    void update(std::uint64_t elapsed_ns) noexcept;

  private:
    struct Target {
        std::size_t input;
        DataModel* model;
    };
    std::vector<SimulatedInput> inputs_;
    std::vector<Target> targets_;
};

}  // namespace mbstorm::slave
