#include "scenario/operation_yaml.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "codec/address.hpp"
#include "codec/function_code.hpp"
#include "codec/limits.hpp"
#include "scenario/scenario.hpp"

namespace mbstorm::scenario {
namespace {

namespace lim = codec::limits;

using codec::RequestShape;

template <RequestShape Shape>
bool shape_is(std::uint8_t fc) noexcept {
    return codec::request_is(fc, Shape);
}

// The public functions `pred` admits, as codes ("0x05, 0x06") or labels ("0x05
// write_single_coil, ...") for "X does not apply to F (only to ...)".
template <typename Pred>
std::string functions_where(Pred pred, bool labels) {
    std::string text;
    for (const codec::FunctionInfo& f : codec::public_functions()) {
        const std::uint8_t fc = codec::to_byte(f.code);
        if (!pred(fc)) continue;
        if (!text.empty()) text += ", ";
        text += labels ? codec::function_label(fc) : fmt::format("0x{:02X}", fc);
    }
    return text;
}

std::uint8_t parse_function(const YamlReader& r, const YAML::Node& n) {
    const std::string text = r.scalar(n, "function");
    std::uint8_t fc = 0;
    if (auto error = codec::parse_function_code(text, fc); !error.empty())
        r.fail(n, fmt::format("{} (generated: {})", error, load::generatable_functions_text()));
    if (!load::is_generatable_function(fc)) {
        r.fail(n, fmt::format("function {} cannot be generated (valid: {})",
                              codec::function_label(fc), load::generatable_functions_text()));
    }
    return fc;
}

// One rule for addresses everywhere: codec/address.hpp.
void parse_address(const YamlReader& r, const YAML::Node& n, load::Operation& op) {
    const std::string text = r.scalar(n, "address");
    codec::AddressRange range;
    const std::string error = codec::parse_address_range(text, function_table(op.function), range);
    if (!error.empty()) r.fail(n, fmt::format("address {}", error));
    op.first_address = range.first;
    op.last_address.reset();
    if (range.is_range) op.last_address = range.last;
}

load::ValueSpec parse_values(const YamlReader& r, const YAML::Node& n) {
    load::ValueSpec spec;
    if (n.IsScalar()) {
        const std::string s = n.Scalar();
        if (s == "random")
            spec.mode = load::ValueMode::Random;
        else if (s == "counter")
            spec.mode = load::ValueMode::Counter;
        else {
            std::int64_t v = 0;
            if (!YamlReader::parse_integer(s, v) || v < 0 || v > 65535) {
                r.fail(n, fmt::format("values: '{}' is not a value 0..65535, random, counter or a "
                                      "mapping {{mode: constant|counter|random|pattern, ...}}",
                                      s));
            }
            spec.value = static_cast<std::uint16_t>(v);
        }
        return spec;
    }
    NodeSlot mode_node;
    r.each_key(
        n, "values", {"mode", "value", "start", "step", "pattern"},
        [&](const std::string& key, const YAML::Node&, const YAML::Node& v) {
            if (key == "mode") {
                mode_node = v;
                const std::string m =
                    r.choice(v, "values.mode", {"constant", "counter", "random", "pattern"});
                spec.mode = m == "constant"  ? load::ValueMode::Constant
                            : m == "counter" ? load::ValueMode::Counter
                            : m == "random"  ? load::ValueMode::Random
                                             : load::ValueMode::Pattern;
            } else if (key == "value" || key == "start") {
                spec.value = static_cast<std::uint16_t>(r.integer(v, "values." + key, 0, 65535));
            } else if (key == "step") {
                spec.step = static_cast<std::uint16_t>(r.integer(v, "values.step", 0, 65535));
            } else {
                if (!v.IsSequence() || v.size() == 0) {
                    r.fail(v, "values.pattern must be a list of at least one value 0..65535");
                }
                if (v.size() > kMaxListEntries) {
                    r.fail(v[kMaxListEntries],
                           fmt::format("values.pattern has {} entries (at most {})", v.size(),
                                       kMaxListEntries));
                }
                for (const auto& item : v) {
                    spec.pattern.push_back(static_cast<std::uint16_t>(
                        r.integer(item, "values.pattern entry", 0, 65535)));
                }
            }
        });
    if (!mode_node) {
        // The keys given say which mode is meant.
        if (!spec.pattern.empty())
            spec.mode = load::ValueMode::Pattern;
        else if (n["start"] || n["step"])
            spec.mode = load::ValueMode::Counter;
    }
    if (spec.mode == load::ValueMode::Pattern && spec.pattern.empty()) {
        r.fail(n, "values: mode pattern needs `pattern: [v1, v2, ...]` (at least one value)");
    }
    if (!spec.pattern.empty() && spec.mode != load::ValueMode::Pattern) {
        r.fail(n, "values: `pattern` is only used with mode: pattern");
    }
    return spec;
}

Expectation parse_expect(const YamlReader& r, const YAML::Node& n, const load::Operation& op) {
    if (!can_expect(op.function)) {
        r.fail(n,
               fmt::format("expect: {} returns no values to check (valid for {})",
                           codec::function_label(op.function), functions_where(can_expect, true)));
    }
    const bool bits = codec::response_is(op.function, codec::ResponseShape::Bits);
    const std::int64_t hi = bits ? 1 : 65535;
    Expectation e;
    e.active = true;
    e.first_address = op.first_address;
    NodeSlot values_node;
    r.each_key(n, "expect", {"value", "min", "max", "values"},
               [&](const std::string& key, const YAML::Node&, const YAML::Node& v) {
                   const std::string what = "expect." + key;
                   if (key == "value")
                       e.value = static_cast<std::uint16_t>(r.integer(v, what, 0, hi));
                   else if (key == "min")
                       e.min = static_cast<std::uint16_t>(r.integer(v, what, 0, hi));
                   else if (key == "max")
                       e.max = static_cast<std::uint16_t>(r.integer(v, what, 0, hi));
                   else {
                       values_node = v;
                       if (!v.IsSequence() || v.size() == 0) {
                           r.fail(v, fmt::format("{} must be a list of values 0..{}", what, hi));
                       }
                       if (v.size() > kMaxListEntries) {
                           r.fail(v[kMaxListEntries], fmt::format("{} has {} entries (at most {})",
                                                                  what, v.size(), kMaxListEntries));
                       }
                       for (const auto& item : v) {
                           e.values.push_back(static_cast<std::uint16_t>(
                               r.integer(item, "expect.values entry", 0, hi)));
                       }
                   }
               });
    if (!e.value && !e.min && !e.max && e.values.empty()) {
        r.fail(n, "expect: give at least one of value, min, max, values");
    }
    if (e.min && e.max && *e.min > *e.max) {
        r.fail(n, fmt::format("expect: min {} is greater than max {}", *e.min, *e.max));
    }
    if (values_node) {
        const std::uint32_t span = op.quantity;
        const std::uint32_t last = op.last_address ? *op.last_address : op.first_address + span - 1;
        const std::uint32_t needed = last - op.first_address + 1;
        if (e.values.size() < needed) {
            r.fail(values_node, fmt::format("expect.values has {} entries but the operation reads "
                                            "addresses {}..{} ({} needed, one per address)",
                                            e.values.size(), op.first_address, last, needed));
        }
    }
    return e;
}

}  // namespace

std::optional<codec::Table> function_table(std::uint8_t fc) noexcept {
    return codec::function_table(fc);
}

QuantityLimits quantity_limits(std::uint8_t fc) noexcept {
    return codec::quantity_range(fc);
}

bool takes_values(std::uint8_t fc) noexcept {
    const codec::FunctionInfo* f = codec::function_info(fc);
    if (f == nullptr) return false;
    switch (f->request) {
        case RequestShape::SingleCoil:
        case RequestShape::SingleRegister:
        case RequestShape::MultipleCoils:
        case RequestShape::MultipleRegisters:
        case RequestShape::MaskWrite:
        case RequestShape::ReadWriteRegisters:
            return true;
        case RequestShape::FunctionOnly:
        case RequestShape::AddressQuantity:
        case RequestShape::SubFunction:
        case RequestShape::FileRecords:
        case RequestShape::FifoPointer:
        case RequestShape::MeiTransport:
            return false;
    }
    return false;
}

namespace {

// An operation's keys read in any order; what depends on several is checked once all are read.
struct OperationKeys {
    const YamlReader& r;
    ParsedOperation& out;
    QuantityLimits q;
    std::string fname;
    NodeSlot address{}, quantity{}, expect{}, thresholds{}, zipf{};

    // `key` is refused unless `ok`: it does not apply to this function.
    void only_for(const YAML::Node& key_node, const std::string& key, bool ok,
                  const std::string& valid) const {
        if (!ok)
            r.fail(key_node,
                   fmt::format("{} does not apply to {} (only to {})", key, fname, valid));
    }
    void read(const std::string& key, const YAML::Node& key_node, const YAML::Node& v);
    // The keys only some request shapes have; false for any other key.
    bool read_shape_key(const std::string& key, const YAML::Node& key_node, const YAML::Node& v);
};

bool OperationKeys::read_shape_key(const std::string& key, const YAML::Node& key_node,
                                   const YAML::Node& v) {
    load::Operation& op = out.operation;
    if (key == "values") {
        only_for(key_node, key, takes_values(op.function),
                 "writes: " + functions_where(takes_values, false));
        op.values = parse_values(r, v);
    } else if (key == "write_quantity") {
        only_for(key_node, key, codec::request_is(op.function, RequestShape::ReadWriteRegisters),
                 functions_where(shape_is<RequestShape::ReadWriteRegisters>, true));
        op.write_quantity = static_cast<std::uint16_t>(
            r.integer(v, "write_quantity", 1, lim::kMaxRwWriteRegisters));
    } else if (key == "and_mask") {
        only_for(key_node, key, codec::request_is(op.function, RequestShape::MaskWrite),
                 functions_where(shape_is<RequestShape::MaskWrite>, true));
        op.and_mask = static_cast<std::uint16_t>(r.integer(v, "and_mask", 0, 65535));
    } else if (key == "device_id_code") {
        only_for(key_node, key, codec::request_is(op.function, RequestShape::MeiTransport),
                 functions_where(shape_is<RequestShape::MeiTransport>, true));
        op.device_id_code = static_cast<std::uint8_t>(
            r.integer(v, "device_id_code", lim::kMinDeviceIdCode, lim::kMaxDeviceIdCode));
    } else {
        return false;
    }
    return true;
}

void OperationKeys::read(const std::string& key, const YAML::Node& key_node, const YAML::Node& v) {
    load::Operation& op = out.operation;
    if (read_shape_key(key, key_node, v)) return;
    if (key == "name") {
        op.name = r.scalar(v, "name");
        if (op.name.empty()) r.fail(v, "name must not be empty");
        out.named = true;
    } else if (key == "unit") {
        op.unit_id = static_cast<std::uint8_t>(r.integer(v, "unit", 0, 255));
    } else if (key == "address") {
        only_for(key_node, key, function_table(op.function).has_value(),
                 "functions with an address: " +
                     functions_where([](std::uint8_t fc) { return function_table(fc).has_value(); },
                                     false));
        address = v;
    } else if (key == "quantity") {
        only_for(key_node, key, q.max != 0,
                 "functions with a quantity: " +
                     functions_where([](std::uint8_t fc) { return quantity_limits(fc).max != 0; },
                                     false));
        quantity = v;
        op.quantity = static_cast<std::uint16_t>(
            r.integer(v, fmt::format("quantity for {}", fname), q.min, q.max));
    } else if (key == "distribution") {
        const std::string d = r.choice(v, "distribution", {"sequential", "uniform", "zipf"});
        op.address_mode = d == "uniform" ? load::AddressMode::Uniform
                          : d == "zipf"  ? load::AddressMode::Zipf
                                         : load::AddressMode::Sequential;
    } else if (key == "zipf_exponent") {
        zipf = v;
        op.zipf_exponent = r.number(v, "zipf_exponent", 0, load::kMaxZipfExponent);
        if (op.zipf_exponent <= 0)
            r.fail(v, fmt::format("zipf_exponent: 0 is out of range (valid > 0 and <= {:g})",
                                  load::kMaxZipfExponent));
    } else if (key == "weight") {
        op.weight = static_cast<std::uint32_t>(r.integer(v, "weight", 1, 4294967295LL));
    } else if (key == "expect") {
        expect = v;
    } else if (key == "thresholds") {
        thresholds = v;
    }  // "function": read first
}

// The whole block must fit the address space and the range.
void check_address_block(const YamlReader& r, const YAML::Node& at, const load::Operation& op) {
    const std::uint32_t span = load::address_span(op);
    if (op.first_address + span - 1 > 0xFFFF) {
        r.fail(at, fmt::format("address {} + quantity {} runs past 65535 (the first address "
                               "must be <= {})",
                               op.first_address, span, 0x10000 - span));
    }
    if (op.last_address && *op.last_address - op.first_address + 1U < span) {
        r.fail(at, fmt::format("address range {}-{} holds {} items but each request needs {} "
                               "(widen the range or lower the quantity)",
                               op.first_address, *op.last_address,
                               *op.last_address - op.first_address + 1, span));
    }
}

std::vector<ThresholdSpec> parse_operation_thresholds(const YamlReader& r, const YAML::Node& n) {
    if (!n.IsSequence()) r.fail(n, "thresholds must be a list of expressions like \"p99 < 5ms\"");
    if (n.size() > kMaxThresholds) {
        r.fail(n[kMaxThresholds],
               fmt::format("too many thresholds: {} (at most {})", n.size(), kMaxThresholds));
    }
    std::vector<ThresholdSpec> out;
    for (const auto& t : n) {
        Result<ThresholdSpec> spec = parse_threshold(r.scalar(t, "threshold"));
        if (!spec.ok()) r.fail(t, spec.error().message());
        out.push_back(std::move(spec).value());
    }
    return out;
}

}  // namespace

ParsedOperation parse_operation(const YamlReader& r, const YAML::Node& node, std::size_t index) {
    ParsedOperation out;
    load::Operation& op = out.operation;
    const std::string what = fmt::format("operations[{}]", index);
    if (!node.IsMap()) r.fail(node, what + " must be a mapping (function, address, quantity, ...)");
    // The function decides what the other keys mean, so read it first.
    if (const YAML::Node fn = node["function"]) {
        op.function = parse_function(r, fn);
    } else {
        r.fail(node, what +
                         ": `function` is required (a number like 3 or a name like "
                         "read_holding_registers)");
    }
    OperationKeys keys{r, out, quantity_limits(op.function), codec::function_label(op.function)};
    op.quantity = keys.q.max == 1 ? 1 : 10;
    r.each_key(node, what,
               {"name", "function", "unit", "address", "quantity", "distribution", "zipf_exponent",
                "values", "weight", "write_quantity", "and_mask", "device_id_code", "expect",
                "thresholds"},
               [&](const std::string& key, const YAML::Node& key_node, const YAML::Node& v) {
                   keys.read(key, key_node, v);
               });
    if (keys.zipf && op.address_mode != load::AddressMode::Zipf)
        r.fail(keys.zipf, "zipf_exponent is only used with distribution: zipf");
    if (keys.address) parse_address(r, keys.address, op);
    if (function_table(op.function)) {
        check_address_block(r,
                            keys.address    ? keys.address.node
                            : keys.quantity ? keys.quantity.node
                                            : node,
                            op);
    }
    if (op.name.empty()) op.name = std::string(codec::function_name(op.function));
    if (keys.expect) out.expect = parse_expect(r, keys.expect, op);
    if (keys.thresholds) out.thresholds = parse_operation_thresholds(r, keys.thresholds);
    return out;
}

}  // namespace mbstorm::scenario
