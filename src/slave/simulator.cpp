#include "slave/simulator.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <numbers>

namespace mbstorm::slave {

namespace {

std::uint64_t mix64(std::uint64_t z) noexcept {
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

// Position inside the current period, in [0, 1).
double phase_of(std::uint64_t elapsed_ns, std::uint64_t period_ns) noexcept {
    return static_cast<double>(elapsed_ns % period_ns) / static_cast<double>(period_ns);
}

}  // namespace

void encode_value(double v, ValueType type, std::uint16_t* regs) noexcept {
    if (std::isnan(v)) v = 0.0;
    switch (type) {
        case ValueType::UInt16:
            regs[0] = static_cast<std::uint16_t>(std::clamp(std::nearbyint(v), 0.0, 65535.0));
            return;
        case ValueType::Int16:
            regs[0] = static_cast<std::uint16_t>(
                static_cast<std::int16_t>(std::clamp(std::nearbyint(v), -32768.0, 32767.0)));
            return;
        case ValueType::Float32: {
            const auto bits = std::bit_cast<std::uint32_t>(static_cast<float>(v));
            regs[0] = static_cast<std::uint16_t>(bits >> 16);
            regs[1] = static_cast<std::uint16_t>(bits);
            return;
        }
    }
}

double simulated_value(const SimulatedInput& in, std::uint64_t elapsed_ns) noexcept {
    const std::uint64_t period = in.period_ns == 0 ? 1 : in.period_ns;
    switch (in.wave) {
        case Waveform::Ramp:
            return in.offset + in.amplitude * phase_of(elapsed_ns, period);
        case Waveform::Sine: {
            const double x = phase_of(elapsed_ns, period) + in.phase;
            return in.offset + in.amplitude * std::sin(2.0 * std::numbers::pi * x);
        }
        case Waveform::Square:
            return in.offset + (phase_of(elapsed_ns, period) < in.duty ? in.amplitude : 0.0);
        case Waveform::Random: {
            const std::uint64_t tick = elapsed_ns / period;
            const std::uint64_t r = mix64(in.seed * 0x9e3779b97f4a7c15ULL + tick + 1);
            const double u = static_cast<double>(r >> 11) * 0x1.0p-53;
            if (in.type == ValueType::Float32) return in.min + u * (in.max - in.min);
            // Integers: every value in [min, max] equally likely.
            return in.min + std::floor(u * (in.max - in.min + 1.0));
        }
        case Waveform::Counter:
            return in.offset + in.step * static_cast<double>(elapsed_ns / period);
    }
    return 0.0;
}

Simulator::Simulator(std::vector<SimulatedInput> inputs, const UnitModels& units)
    : inputs_(std::move(inputs)) {
    for (std::size_t i = 0; i < inputs_.size(); ++i) {
        for (std::size_t m = 0; m < units.model_count(); ++m) {
            DataModel& model = units.model_at(m);
            const auto& wanted = inputs_[i].units;
            bool selected = wanted.empty() || units.is_shared();
            for (std::uint8_t u : wanted) selected = selected || units.find(u) == &model;
            if (selected) targets_.push_back({i, &model});
        }
    }
}

void Simulator::update(std::uint64_t elapsed_ns) noexcept {
    for (const Target& t : targets_) {
        const SimulatedInput& in = inputs_[t.input];
        double v = simulated_value(in, elapsed_ns);
        std::uint16_t regs[2] = {0, 0};
        if (in.wave == Waveform::Counter && in.type != ValueType::Float32) {
            // Counters wrap like a real 16-bit counter instead of sticking at the limit.
            const double wrapped = std::fmod(std::nearbyint(v), 65536.0);
            regs[0] = static_cast<std::uint16_t>(
                static_cast<std::int64_t>(wrapped < 0 ? wrapped + 65536.0 : wrapped));
        } else {
            encode_value(v, in.type, regs);
        }
        switch (in.table) {
            case Table::Coils:
                t.model->coils().set(in.address, v != 0.0);
                break;
            case Table::DiscreteInputs:
                t.model->discrete_inputs().set(in.address, v != 0.0);
                break;
            case Table::InputRegisters:
            case Table::HoldingRegisters: {
                RegisterTable& table = in.table == Table::InputRegisters
                                           ? t.model->input_registers()
                                           : t.model->holding_registers();
                for (std::uint32_t k = 0; k < value_width(in.type); ++k) {
                    table.set(static_cast<std::uint16_t>(in.address + k), regs[k]);
                }
                break;
            }
        }
    }
}

}  // namespace mbstorm::slave
