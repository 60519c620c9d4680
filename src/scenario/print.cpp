#include "scenario/print.hpp"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include "codec/address.hpp"
#include "codec/function_code.hpp"
#include "scenario/operation_yaml.hpp"
#include "scenario/yaml_reader.hpp"
#include "slave/device_yaml_print.hpp"

namespace mbstorm::scenario {
namespace {

std::string number_text(double v) {
    return fmt::format("{:.17g}", v);
}

const char* value_mode_name(load::ValueMode m) {
    switch (m) {
        case load::ValueMode::Constant:
            return "constant";
        case load::ValueMode::Counter:
            return "counter";
        case load::ValueMode::Random:
            return "random";
        case load::ValueMode::Pattern:
            return "pattern";
    }
    return "constant";
}

void emit_operation(YAML::Emitter& out, const load::Operation& op, const Expectation& e,
                    const std::vector<ThresholdSpec>& thresholds) {
    out << YAML::BeginMap;
    out << YAML::Key << "name" << YAML::Value << op.name;
    out << YAML::Key << "function" << YAML::Value << std::string(codec::function_name(op.function));
    out << YAML::Key << "unit" << YAML::Value << static_cast<int>(op.unit_id);
    if (function_table(op.function)) {
        std::string address = codec::format_protocol_address(op.first_address);
        if (op.last_address) address += "-" + codec::format_protocol_address(*op.last_address);
        out << YAML::Key << "address" << YAML::Value << address << YAML::Comment("0-based");
    }
    if (quantity_limits(op.function).max != 0) {
        out << YAML::Key << "quantity" << YAML::Value << op.quantity;
    }
    using codec::RequestShape;
    if (codec::request_is(op.function, RequestShape::ReadWriteRegisters))
        out << YAML::Key << "write_quantity" << YAML::Value << op.write_quantity;
    if (codec::request_is(op.function, RequestShape::MaskWrite))
        out << YAML::Key << "and_mask" << YAML::Value << op.and_mask;
    if (codec::request_is(op.function, RequestShape::MeiTransport)) {
        out << YAML::Key << "device_id_code" << YAML::Value << static_cast<int>(op.device_id_code);
    }
    out << YAML::Key << "distribution" << YAML::Value << address_mode_name(op.address_mode);
    if (op.address_mode == load::AddressMode::Zipf) {
        out << YAML::Key << "zipf_exponent" << YAML::Value << number_text(op.zipf_exponent);
    }
    if (takes_values(op.function)) {
        out << YAML::Key << "values" << YAML::Value << YAML::Flow << YAML::BeginMap;
        out << YAML::Key << "mode" << YAML::Value << value_mode_name(op.values.mode);
        switch (op.values.mode) {
            case load::ValueMode::Constant:
                out << YAML::Key << "value" << YAML::Value << op.values.value;
                break;
            case load::ValueMode::Counter:
                out << YAML::Key << "start" << YAML::Value << op.values.value;
                out << YAML::Key << "step" << YAML::Value << op.values.step;
                break;
            case load::ValueMode::Random:
                break;
            case load::ValueMode::Pattern:
                out << YAML::Key << "pattern" << YAML::Value << YAML::Flow << op.values.pattern;
                break;
        }
        out << YAML::EndMap;
    }
    out << YAML::Key << "weight" << YAML::Value << op.weight;
    if (e.active) {
        out << YAML::Key << "expect" << YAML::Value << YAML::Flow << YAML::BeginMap;
        if (e.value) out << YAML::Key << "value" << YAML::Value << *e.value;
        if (e.min) out << YAML::Key << "min" << YAML::Value << *e.min;
        if (e.max) out << YAML::Key << "max" << YAML::Value << *e.max;
        if (!e.values.empty())
            out << YAML::Key << "values" << YAML::Value << YAML::Flow << e.values;
        out << YAML::EndMap;
    }
    if (!thresholds.empty()) {
        out << YAML::Key << "thresholds" << YAML::Value << YAML::BeginSeq;
        for (const auto& t : thresholds) out << YAML::DoubleQuoted << t.text;
        out << YAML::EndSeq;
    }
    out << YAML::EndMap;
}

// The stages (none without), the operations with the thresholds written under them, and the
// top-level thresholds: each threshold where the scenario wrote it (ThresholdSpec::in_operation).
void emit_stages(YAML::Emitter& out, const Scenario& s) {
    if (!s.stages.empty()) {
        out << YAML::Key << "stages" << YAML::Value << YAML::BeginSeq;
        for (const auto& st : s.stages) {
            out << YAML::Flow << YAML::BeginMap;
            out << YAML::Key << "name" << YAML::Value << st.name;
            out << YAML::Key << "duration" << YAML::Value << duration_text(st.duration);
            if (st.rate) out << YAML::Key << "rate" << YAML::Value << number_text(*st.rate);
            if (st.connections) out << YAML::Key << "connections" << YAML::Value << *st.connections;
            out << YAML::Key << "ramp" << YAML::Value
                << (st.ramp == load::Ramp::Constant ? "constant" : "linear");
            out << YAML::EndMap;
        }
        out << YAML::EndSeq;
    }
}

void emit_operations(YAML::Emitter& out, const Scenario& s) {
    const load::Plan& p = s.plan;
    out << YAML::Key << "operations" << YAML::Value << YAML::BeginSeq;
    for (std::size_t i = 0; i < p.operations.size(); ++i) {
        std::vector<ThresholdSpec> own;
        for (const auto& t : s.thresholds) {
            if (t.in_operation && t.operation == p.operations[i].name) own.push_back(t);
        }
        emit_operation(out, p.operations[i],
                       i < s.expectations.size() ? s.expectations[i] : Expectation{}, own);
    }
    out << YAML::EndSeq;
}

void emit_top_level_thresholds(YAML::Emitter& out, const Scenario& s) {
    bool any_top_level = false;
    for (const auto& t : s.thresholds) any_top_level = any_top_level || !t.in_operation;
    if (any_top_level) {
        out << YAML::Key << "thresholds" << YAML::Value << YAML::BeginSeq;
        for (const auto& t : s.thresholds) {
            if (t.in_operation) continue;
            if (t.operation.empty()) {
                out << YAML::DoubleQuoted << t.text;
                continue;
            }
            out << YAML::Flow << YAML::BeginMap << YAML::Key << "operation" << YAML::Value
                << t.operation << YAML::Key << "check" << YAML::Value << YAML::DoubleQuoted
                << t.text << YAML::EndMap;
        }
        out << YAML::EndSeq;
    }
}

}  // namespace

const char* address_mode_name(load::AddressMode m) {
    switch (m) {
        case load::AddressMode::Sequential:
            return "sequential";
        case load::AddressMode::Uniform:
            return "uniform";
        case load::AddressMode::Zipf:
            return "zipf";
    }
    return "sequential";
}

std::string format_scenario(const Scenario& s) {
    const load::Plan& p = s.plan;
    YAML::Emitter out;
    out << YAML::Comment(fmt::format("resolved scenario (defaults written out) from {}", s.source));
    out << YAML::BeginMap;
    out << YAML::Key << "name" << YAML::Value << s.name;
    if (!s.description.empty()) out << YAML::Key << "description" << YAML::Value << s.description;
    if (!s.target.empty()) {
        out << YAML::Key << "target" << YAML::Value << s.target;
    }
    if (p.framing == codec::Framing::Rtu)
        out << YAML::Key << "transport" << YAML::Value << "rtu-over-tcp";
    if (s.target.empty()) {
        out << YAML::Key << "slave_threads" << YAML::Value << s.slave_threads
            << YAML::Comment("no target: the embedded reference slave (0 = half the cores)");
        out << YAML::Key << "slave" << YAML::Value;
        slave::emit_device_yaml(out, s.slave);
    }
    if (!p.source_addresses.empty())
        out << YAML::Key << "source_addr" << YAML::Value << p.source_addresses;
    out << YAML::Key << "threads" << YAML::Value << p.threads << YAML::Comment("0 = one per core");
    out << YAML::Key << "connections" << YAML::Value << p.connections;
    out << YAML::Key << "depth" << YAML::Value << p.depth;
    const bool open = p.model == load::LoadModel::OpenLoop;
    out << YAML::Key << "model" << YAML::Value << (open ? "open" : "closed");
    if (open) {
        out << YAML::Key << "rate" << YAML::Value << number_text(p.rate);
        out << YAML::Key << "arrival" << YAML::Value
            << (p.arrival == load::Arrival::Poisson ? "poisson" : "even");
        out << YAML::Key << "late_threshold" << YAML::Value << duration_text(p.late_threshold);
    }
    if (s.stages.empty()) {
        out << YAML::Key << "duration" << YAML::Value << duration_text(p.duration);
        out << YAML::Key << "transactions" << YAML::Value << p.transactions;
    }
    out << YAML::Key << "warmup" << YAML::Value << duration_text(p.warmup);
    out << YAML::Key << "timeout" << YAML::Value << duration_text(p.transaction_timeout);
    out << YAML::Key << "connect_timeout" << YAML::Value << duration_text(p.connect_timeout);
    out << YAML::Key << "connect_rate" << YAML::Value << number_text(p.connect_rate);
    out << YAML::Key << "reconnect_backoff" << YAML::Value << YAML::Flow << YAML::BeginMap
        << YAML::Key << "min" << YAML::Value << duration_text(p.reconnect_backoff_min) << YAML::Key
        << "max" << YAML::Value << duration_text(p.reconnect_backoff_max) << YAML::EndMap;
    out << YAML::Key << "allow_writes" << YAML::Value << p.allow_writes;
    out << YAML::Key << "seed" << YAML::Value << p.seed;
    emit_stages(out, s);
    emit_operations(out, s);
    emit_top_level_thresholds(out, s);
    out << YAML::EndMap;
    return std::string(out.c_str()) + "\n";
}

}  // namespace mbstorm::scenario
