#include "slave/device_yaml_print.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <charconv>
#include <cstdio>

#include "codec/address.hpp"
#include "codec/function_set.hpp"

namespace mbstorm::slave {

namespace {

// Shortest text that parses back to exactly `v` (std::to_chars round-trip guarantee).
std::string number_text(double v) {
    char buf[64];
    const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
    return ec == std::errc() ? std::string(buf, end) : std::string("0");
}

// Nanoseconds as the milliseconds the parser takes ("1.5" for 1'500'000 ns): exact decimal,
// so parsing rounds back to the same nanosecond count.
std::string millis_text(std::uint64_t ns) {
    std::string text = std::to_string(ns / 1'000'000);
    if (const std::uint64_t frac = ns % 1'000'000; frac != 0) {
        char digits[8];
        std::snprintf(digits, sizeof digits, "%06llu", static_cast<unsigned long long>(frac));
        std::string f = digits;
        f.erase(f.find_last_not_of('0') + 1);
        text += "." + f;
    }
    return text;
}

const char* type_name(ValueType t) {
    switch (t) {
        case ValueType::UInt16:
            return "uint16";
        case ValueType::Int16:
            return "int16";
        case ValueType::Float32:
            return "float32";
    }
    return "uint16";
}

const char* wave_name(Waveform w) {
    switch (w) {
        case Waveform::Ramp:
            return "ramp";
        case Waveform::Sine:
            return "sine";
        case Waveform::Square:
            return "square";
        case Waveform::Random:
            return "random";
        case Waveform::Counter:
            return "counter";  // never written: interval counters go under `counters:`
    }
    return "sine";
}

const char* policy_name(UnknownUnitPolicy p) {
    switch (p) {
        case UnknownUnitPolicy::GatewayTargetFailed:
            return "gateway_target_failed";
        case UnknownUnitPolicy::GatewayPathUnavailable:
            return "gateway_path_unavailable";
        case UnknownUnitPolicy::Ignore:
            return "ignore";
    }
    return "gateway_target_failed";
}

std::string hex_text(unsigned v) {
    char buf[8];
    std::snprintf(buf, sizeof buf, "0x%02X", v);
    return buf;
}

// A unit list in the order given, consecutive ids folded into "a-b" ranges (which the parser
// expands back to the same sequence).
void emit_units(YAML::Emitter& out, const std::vector<std::uint8_t>& ids) {
    out << YAML::Flow << YAML::BeginSeq;
    for (std::size_t i = 0; i < ids.size();) {
        std::size_t j = i;
        while (j + 1 < ids.size() && ids[j + 1] == ids[j] + 1) ++j;
        if (j - i >= 2) {
            out << std::to_string(ids[i]) + "-" + std::to_string(ids[j]);
        } else {
            for (std::size_t k = i; k <= j; ++k) out << static_cast<int>(ids[k]);
        }
        i = j + 1;
    }
    out << YAML::EndSeq;
}

void emit_entry_units(YAML::Emitter& out, const std::vector<std::uint8_t>& ids) {
    if (ids.empty()) return;  // every model; the parser has no spelling for an empty filter
    out << YAML::Key << "units" << YAML::Value;
    emit_units(out, ids);
}

void emit_identification(YAML::Emitter& out, const DeviceIdentity& ident) {
    out << YAML::BeginMap;
    for (const IdentificationKey& named : identification_keys()) {
        out << YAML::Key << named.key << YAML::Value << YAML::DoubleQuoted
            << ident.get(named.object_id);
    }
    bool any_extended = false;
    for (unsigned id = 0x80; id <= 0xFF; ++id) {
        any_extended = any_extended || !ident.get(static_cast<std::uint8_t>(id)).empty();
    }
    out << YAML::Key << "extended" << YAML::Value;
    if (!any_extended) out << YAML::Flow;  // `{}`
    out << YAML::BeginMap;
    for (unsigned id = 0x80; id <= 0xFF; ++id) {
        const std::string& value = ident.get(static_cast<std::uint8_t>(id));
        if (!value.empty()) {
            out << YAML::Key << hex_text(id) << YAML::Value << YAML::DoubleQuoted << value;
        }
    }
    out << YAML::EndMap;
    out << YAML::EndMap;
}

// Printable ASCII as a string (as usually written), anything else as a list of bytes.
void emit_server_id(YAML::Emitter& out, const std::vector<std::uint8_t>& id) {
    const bool printable =
        std::all_of(id.begin(), id.end(), [](std::uint8_t b) { return b >= 0x20 && b < 0x7F; });
    if (printable) {
        out << YAML::DoubleQuoted << std::string(id.begin(), id.end());
        return;
    }
    out << YAML::Flow << YAML::BeginSeq;
    for (std::uint8_t b : id) out << static_cast<int>(b);
    out << YAML::EndSeq;
}

// Block style for lists with entries, `[]` for none (block style would print an empty line).
void begin_list(YAML::Emitter& out, bool empty) {
    if (empty) out << YAML::Flow;
    out << YAML::BeginSeq;
}

void emit_init(YAML::Emitter& out, const std::vector<InitRange>& init) {
    begin_list(out, init.empty());
    for (const InitRange& r : init) {
        out << YAML::Flow << YAML::BeginMap;
        out << YAML::Key << "table" << YAML::Value << table_name(r.table);
        out << YAML::Key << "address" << YAML::Value << codec::format_protocol_address(r.address);
        const bool repeated =
            r.words.size() > 1 && std::all_of(r.words.begin(), r.words.end(),
                                              [&](std::uint16_t w) { return w == r.words[0]; });
        if (repeated) {
            out << YAML::Key << "value" << YAML::Value << r.words[0];
            out << YAML::Key << "count" << YAML::Value << r.words.size();
        } else {
            out << YAML::Key << "values" << YAML::Value << YAML::Flow << YAML::BeginSeq;
            for (std::uint16_t w : r.words) out << w;
            out << YAML::EndSeq;
        }
        emit_entry_units(out, r.units);
        out << YAML::EndMap;
    }
    out << YAML::EndSeq;
}

void emit_counters(YAML::Emitter& out, const DeviceDescription& d) {
    const bool interval =
        std::any_of(d.simulated.begin(), d.simulated.end(),
                    [](const SimulatedInput& s) { return s.wave == Waveform::Counter; });
    begin_list(out, d.read_counters.empty() && !interval);
    for (const ReadCounterSpec& c : d.read_counters) {
        out << YAML::Flow << YAML::BeginMap;
        out << YAML::Key << "table" << YAML::Value << table_name(c.table);
        out << YAML::Key << "address" << YAML::Value << codec::format_protocol_address(c.address);
        out << YAML::Key << "mode" << YAML::Value << "read";
        // Steps wrap at 16 bits; written signed so a countdown reads as one (65533 -> -3).
        out << YAML::Key << "step" << YAML::Value << static_cast<std::int16_t>(c.step);
        out << YAML::Key << "start" << YAML::Value << c.start;
        emit_entry_units(out, c.units);
        out << YAML::EndMap;
    }
    for (const SimulatedInput& s : d.simulated) {
        if (s.wave != Waveform::Counter) continue;
        out << YAML::Flow << YAML::BeginMap;
        out << YAML::Key << "table" << YAML::Value << table_name(s.table);
        out << YAML::Key << "address" << YAML::Value << codec::format_protocol_address(s.address);
        out << YAML::Key << "mode" << YAML::Value << "interval";
        out << YAML::Key << "interval_ms" << YAML::Value << millis_text(s.period_ns);
        out << YAML::Key << "type" << YAML::Value << type_name(s.type);
        out << YAML::Key << "step" << YAML::Value << number_text(s.step);
        out << YAML::Key << "start" << YAML::Value << number_text(s.offset);
        emit_entry_units(out, s.units);
        out << YAML::EndMap;
    }
    out << YAML::EndSeq;
}

void emit_simulate(YAML::Emitter& out, const std::vector<SimulatedInput>& inputs) {
    begin_list(out, std::all_of(inputs.begin(), inputs.end(), [](const SimulatedInput& s) {
                   return s.wave == Waveform::Counter;
               }));
    for (const SimulatedInput& s : inputs) {
        if (s.wave == Waveform::Counter) continue;
        out << YAML::Flow << YAML::BeginMap;
        out << YAML::Key << "table" << YAML::Value << table_name(s.table);
        out << YAML::Key << "address" << YAML::Value << codec::format_protocol_address(s.address);
        if (!is_bit_table(s.table)) out << YAML::Key << "type" << YAML::Value << type_name(s.type);
        out << YAML::Key << "wave" << YAML::Value << wave_name(s.wave);
        out << YAML::Key << "period_ms" << YAML::Value << millis_text(s.period_ns);
        out << YAML::Key << "amplitude" << YAML::Value << number_text(s.amplitude);
        out << YAML::Key << "offset" << YAML::Value << number_text(s.offset);
        out << YAML::Key << "phase" << YAML::Value << number_text(s.phase);
        out << YAML::Key << "duty" << YAML::Value << number_text(s.duty);
        out << YAML::Key << "min" << YAML::Value << number_text(s.min);
        out << YAML::Key << "max" << YAML::Value << number_text(s.max);
        out << YAML::Key << "seed" << YAML::Value << s.seed;
        emit_entry_units(out, s.units);
        out << YAML::EndMap;
    }
    out << YAML::EndSeq;
}

void emit_delay(YAML::Emitter& out, const DelayConfig& delay) {
    if (delay.kind == DelayConfig::Kind::None) {
        out << "none";
        return;
    }
    out << YAML::Flow << YAML::BeginMap;
    switch (delay.kind) {
        case DelayConfig::Kind::None:
            break;
        case DelayConfig::Kind::Fixed:
            out << YAML::Key << "fixed_ms" << YAML::Value << millis_text(delay.fixed_ns);
            break;
        case DelayConfig::Kind::Uniform:
            out << YAML::Key << "uniform_ms" << YAML::Value << YAML::Flow << YAML::BeginSeq
                << millis_text(delay.min_ns) << millis_text(delay.max_ns) << YAML::EndSeq;
            break;
        case DelayConfig::Kind::Exponential:
            out << YAML::Key << "exponential_mean_ms" << YAML::Value << millis_text(delay.mean_ns);
            break;
    }
    out << YAML::EndMap;
}

void emit_faults(YAML::Emitter& out, const FaultConfig& f) {
    out << YAML::BeginMap;
    out << YAML::Key << "delay" << YAML::Value;
    emit_delay(out, f.delay);
    out << YAML::Key << "stall" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key
        << "duration_ms" << YAML::Value << millis_text(f.stall.duration_ns) << YAML::Key
        << "every_ms" << YAML::Value << millis_text(f.stall.period_ns) << YAML::EndMap;
    out << YAML::Key << "exception" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key
        << "rate" << YAML::Value << number_text(f.exception_rate) << YAML::Key << "code"
        << YAML::Value << static_cast<int>(f.exception_code) << YAML::EndMap;
    out << YAML::Key << "drop_rate" << YAML::Value << number_text(f.drop_rate);
    out << YAML::Key << "no_answer_rate" << YAML::Value << number_text(f.no_answer_rate);
    out << YAML::Key << "seed" << YAML::Value << f.seed;
    out << YAML::EndMap;
}

}  // namespace

void emit_device_yaml(YAML::Emitter& out, const DeviceDescription& d) {
    const ModelConfig& m = d.model;
    out << YAML::BeginMap;
    out << YAML::Key << "tables" << YAML::Value << YAML::Flow << YAML::BeginMap;
    for (Table t :
         {Table::Coils, Table::DiscreteInputs, Table::InputRegisters, Table::HoldingRegisters}) {
        out << YAML::Key << table_name(t) << YAML::Value << m.sizes.of(t);
    }
    out << YAML::EndMap;
    out << YAML::Key << "units" << YAML::Value;
    if (d.shared) {
        out << "shared";
    } else {
        emit_units(out, d.units);
    }
    out << YAML::Key << "unknown_unit" << YAML::Value << policy_name(d.unknown_unit);
    out << YAML::Key << "broadcast_unit_zero" << YAML::Value << d.broadcast_unit_zero;
    out << YAML::Key << "diagnostics" << YAML::Value << m.track_diagnostics;
    out << YAML::Key << "files" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key
        << "count" << YAML::Value << m.file_count << YAML::Key << "records" << YAML::Value
        << m.file_records << YAML::EndMap;
    out << YAML::Key << "exception_status" << YAML::Value << static_cast<int>(m.exception_status);
    out << YAML::Key << "server_id" << YAML::Value;
    emit_server_id(out, m.server_id);
    out << YAML::Key << "run_indicator" << YAML::Value << m.run_indicator_on;
    out << YAML::Key << "identification" << YAML::Value;
    emit_identification(out, m.identity);
    out << YAML::Key << "init" << YAML::Value;
    if (!d.init.empty())
        out << YAML::Comment("as stored: 16-bit words (float32 = 2 each), 0/1 bits");
    emit_init(out, d.init);
    out << YAML::Key << "counters" << YAML::Value;
    emit_counters(out, d);
    out << YAML::Key << "simulate" << YAML::Value;
    emit_simulate(out, d.simulated);
    out << YAML::Key << "faults" << YAML::Value;
    emit_faults(out, d.faults);
    out << YAML::Key << "tls_roles" << YAML::Value << YAML::Flow << YAML::BeginMap;
    for (const auto& [role, set] : d.tls_roles)
        out << YAML::Key << YAML::DoubleQuoted << role << YAML::Value << YAML::DoubleQuoted
            << codec::format_function_set(set);
    out << YAML::EndMap;
    out << YAML::EndMap;
}

std::string format_device_yaml(const DeviceDescription& device) {
    YAML::Emitter out;
    emit_device_yaml(out, device);
    return std::string(out.c_str()) + "\n";
}

}  // namespace mbstorm::slave
