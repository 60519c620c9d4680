#include "slave/device_yaml.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>

#include "codec/address.hpp"
#include "yaml/reader.hpp"

namespace mbstorm::slave {

namespace {

using OptNode = std::optional<YAML::Node>;

// The slave's tables in the codec's terms, for the address rule.
codec::Table codec_table(Table table) {
    switch (table) {
        case Table::Coils:
            return codec::Table::Coils;
        case Table::DiscreteInputs:
            return codec::Table::DiscreteInputs;
        case Table::InputRegisters:
            return codec::Table::InputRegisters;
        case Table::HoldingRegisters:
            break;
    }
    return codec::Table::HoldingRegisters;
}

[[noreturn]] void raise_device_error(const std::string& message, int line, int column) {
    throw DeviceYamlError(message, line, column);
}

// The shared YAML reader (yaml/reader.hpp) raising DeviceYamlError, plus the device's units.
class Parser : public yaml::Reader {
  public:
    explicit Parser(std::string_view source)
        : yaml::Reader(std::string(source), &raise_device_error) {}

    // Calls f(key, value) for each entry of a mapping; keys not in `known` and duplicates
    // fail. f returns false for a key it does not handle, which fails the same way (a key
    // listed but not handled is caught by the tests).
    template <class F>
    void each_key(const YAML::Node& map, std::string_view what,
                  std::span<const std::string_view> known, F&& f) const {
        yaml::Reader::each_key(
            map, what, known,
            [&](const std::string& key, const YAML::Node& key_node, const YAML::Node& v) {
                if (!f(key, v)) fail(key_node, "unknown key '" + key + "' in " + std::string(what));
            });
    }
    template <class F>
    void each_key(const YAML::Node& map, std::string_view what,
                  std::initializer_list<std::string_view> known, F&& f) const {
        each_key(map, what, std::span<const std::string_view>(known.begin(), known.size()), f);
    }

    // The one address rule of every subcommand (codec/address.hpp): a protocol address or a
    // reference number of `table`.
    std::uint16_t address(const YAML::Node& n, Table table) const {
        const std::string s = scalar(n, "address");
        codec::AddressRange range;
        std::string error = codec::parse_address_range(s, codec_table(table), range);
        if (error.empty() && range.is_range) error = "'" + s + "' is a range: give one address";
        if (!error.empty()) fail(n, "address " + error);
        return range.first;
    }

    // Milliseconds (fractions allowed) -> nanoseconds.
    std::uint64_t millis(const YAML::Node& n, std::string_view what) const {
        const double ms = number(n, what);
        if (ms < 0 || ms > 1e12) fail(n, std::string(what) + " must be between 0 and 1e12 ms");
        return static_cast<std::uint64_t>(std::llround(ms * 1e6));
    }

    double rate(const YAML::Node& n, std::string_view what) const {
        const double r = number(n, what);
        if (r < 0.0 || r > 1.0) fail(n, std::string(what) + " must be between 0 and 1");
        return r;
    }
};

Table parse_table(const Parser& p, const YAML::Node& n) {
    const std::string s = p.scalar(n, "table");
    if (s == "coils") return Table::Coils;
    if (s == "discrete_inputs") return Table::DiscreteInputs;
    if (s == "input_registers") return Table::InputRegisters;
    if (s == "holding_registers") return Table::HoldingRegisters;
    p.fail(n, "unknown table '" + s +
                  "' (coils, discrete_inputs, input_registers or holding_registers)");
}

ValueType parse_type(const Parser& p, const YAML::Node& n) {
    const std::string s = p.scalar(n, "type");
    if (s == "uint16") return ValueType::UInt16;
    if (s == "int16") return ValueType::Int16;
    if (s == "float32") return ValueType::Float32;
    p.fail(n, "unknown type '" + s + "' (uint16, int16 or float32)");
}

// One value of `type` as registers; bit tables take 0/1 (or true/false).
void push_value(const Parser& p, const YAML::Node& n, Table table, ValueType type,
                std::vector<std::uint16_t>& words) {
    if (is_bit_table(table)) {
        const std::string s = p.scalar(n, "value");
        if (s == "true" || s == "on") {
            words.push_back(1);
        } else if (s == "false" || s == "off") {
            words.push_back(0);
        } else {
            words.push_back(static_cast<std::uint16_t>(p.integer(n, "bit value", 0, 1)));
        }
        return;
    }
    std::uint16_t regs[2] = {0, 0};
    switch (type) {
        case ValueType::UInt16:
            regs[0] = static_cast<std::uint16_t>(p.integer(n, "uint16 value", 0, 65535));
            break;
        case ValueType::Int16:
            regs[0] = static_cast<std::uint16_t>(
                static_cast<std::int16_t>(p.integer(n, "int16 value", -32768, 32767)));
            break;
        case ValueType::Float32:
            encode_value(p.number(n, "float32 value"), type, regs);
            break;
    }
    for (std::uint32_t k = 0; k < value_width(type); ++k) words.push_back(regs[k]);
}

struct Layout {
    TableSizes sizes;
    bool shared = true;
    std::vector<std::uint8_t> units;
};

void check_fits(const Parser& p, const YAML::Node& where, const Layout& layout, Table table,
                std::uint32_t address, std::uint64_t count) {
    const std::uint32_t size = layout.sizes.of(table);
    if (address + count > size) {
        p.fail(where, "address range " + std::to_string(address) + ".." +
                          std::to_string(address + count - 1) + " does not fit " +
                          table_name(table) + " (size " + std::to_string(size) + ")");
    }
}

std::vector<std::uint8_t> parse_unit_list(const Parser& p, const YAML::Node& n) {
    std::vector<std::uint8_t> ids;
    auto one = [&](const YAML::Node& item) {
        const std::string s = p.scalar(item, "unit id");
        const auto dash = s.find('-', 1);
        if (dash != std::string::npos) {  // "1-10"
            const auto lo = YAML::Node(s.substr(0, dash));
            const auto hi = YAML::Node(s.substr(dash + 1));
            std::int64_t a = 0, b = 0;
            try {
                a = p.integer(lo, "unit id", 0, 255);
                b = p.integer(hi, "unit id", 0, 255);
            } catch (const DeviceYamlError&) {
                p.fail(item, "unit range '" + s + "' must look like 1-10 with ids 0..255");
            }
            if (a > b) p.fail(item, "unit range '" + s + "' is reversed");
            for (std::int64_t u = a; u <= b; ++u) ids.push_back(static_cast<std::uint8_t>(u));
        } else {
            ids.push_back(static_cast<std::uint8_t>(p.integer(item, "unit id", 0, 255)));
        }
    };
    if (n.IsSequence()) {
        for (const auto& item : n) one(item);
    } else {
        one(n);
    }
    if (ids.empty()) p.fail(n, "unit list is empty");
    return ids;
}

// Per-entry `units:` filter; only meaningful with per-unit models.
std::vector<std::uint8_t> parse_entry_units(const Parser& p, const YAML::Node& n,
                                            const Layout& layout) {
    if (layout.shared) {
        p.fail(n, "per-entry 'units' needs per-unit models (a top-level 'units:' list)");
    }
    std::vector<std::uint8_t> ids = parse_unit_list(p, n);
    // Each unit once: a repeated id would only repeat the entry's work.
    std::sort(ids.begin(), ids.end());
    ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
    for (std::uint8_t id : ids) {
        if (!std::binary_search(layout.units.begin(), layout.units.end(), id)) {
            p.fail(n, "unit " + std::to_string(id) + " is not in the top-level 'units' list");
        }
    }
    return ids;
}

void parse_tables(const Parser& p, const YAML::Node& n, TableSizes& sizes) {
    p.each_key(n, "tables", {"coils", "discrete_inputs", "input_registers", "holding_registers"},
               [&](const std::string& key, const YAML::Node& v) {
                   const auto size = static_cast<std::uint32_t>(p.integer(v, key, 0, kFullTable));
                   if (key == "coils") {
                       sizes.coils = size;
                   } else if (key == "discrete_inputs") {
                       sizes.discrete_inputs = size;
                   } else if (key == "input_registers") {
                       sizes.input_registers = size;
                   } else if (key == "holding_registers") {
                       sizes.holding_registers = size;
                   } else {
                       return false;
                   }
                   return true;
               });
}

void parse_files(const Parser& p, const YAML::Node& n, ModelConfig& m) {
    p.each_key(n, "files", {"count", "records"}, [&](const std::string& key, const YAML::Node& v) {
        if (key == "count") {
            m.file_count = static_cast<std::uint16_t>(p.integer(v, "files.count", 0, 65535));
        } else if (key == "records") {
            m.file_records = static_cast<std::uint16_t>(p.integer(v, "files.records", 1, 10000));
        } else {
            return false;
        }
        return true;
    });
    if (std::uint64_t{m.file_count} * m.file_records > 16'000'000) {
        p.fail(n, "files.count * files.records must stay below 16 million registers");
    }
}

void parse_identification(const Parser& p, const YAML::Node& n, DeviceIdentity& ident) {
    auto set = [&](const YAML::Node& v, std::uint8_t id) {
        std::string value = p.scalar(v, "identification object");
        if (value.size() > DeviceIdentity::kMaxObjectLength) {
            p.fail(v, "identification object longer than " +
                          std::to_string(DeviceIdentity::kMaxObjectLength) + " bytes");
        }
        ident.set(id, std::move(value));
    };
    std::vector<std::string_view> keys;
    for (const IdentificationKey& named : identification_keys()) keys.push_back(named.key);
    keys.push_back("extended");
    p.each_key(n, "identification", keys, [&](const std::string& key, const YAML::Node& v) {
        for (const IdentificationKey& named : identification_keys()) {
            if (key == named.key) {
                set(v, named.object_id);
                return true;
            }
        }
        if (key != "extended") return false;
        if (!v.IsMap()) p.fail(v, "identification.extended must be a mapping of id: value");
        for (const auto& kv : v) {
            const auto id = p.integer(kv.first, "extended object id", 0x80, 0xFF);
            set(kv.second, static_cast<std::uint8_t>(id));
        }
        return true;
    });
}

// `random:` of an init entry: `n` values drawn as a simulated random input would be.
void push_random_words(const Parser& p, const YAML::Node& random, ValueType vt, std::int64_t n,
                       InitRange& r) {
    double lo = 0, hi = is_bit_table(r.table) ? 1 : 65535;
    std::uint64_t seed = 1;
    p.each_key(random, "random", {"min", "max", "seed"},
               [&](const std::string& key, const YAML::Node& v) {
                   if (key == "min")
                       lo = p.number(v, "random.min");
                   else if (key == "max")
                       hi = p.number(v, "random.max");
                   else if (key == "seed")
                       seed = static_cast<std::uint64_t>(p.integer(v, "random.seed", 0, INT64_MAX));
                   else
                       return false;
                   return true;
               });
    if (lo > hi) p.fail(random, "random.min must not exceed random.max");
    SimulatedInput gen;
    gen.wave = Waveform::Random;
    gen.type = is_bit_table(r.table) ? ValueType::UInt16 : vt;
    gen.min = lo;
    gen.max = hi;
    gen.seed = seed;
    gen.period_ns = 1;
    for (std::int64_t i = 0; i < n; ++i) {
        std::uint16_t regs[2] = {0, 0};
        encode_value(simulated_value(gen, static_cast<std::uint64_t>(i)), gen.type, regs);
        if (is_bit_table(r.table)) regs[0] = regs[0] != 0;
        for (std::uint32_t k = 0; k < value_width(gen.type); ++k) r.words.push_back(regs[k]);
    }
}

// What init entries may ask of start-up. YAML aliases repeat an entry for a few bytes each, so
// a small file could otherwise hold gigabytes of values or hours of writes: every register of
// every unit written once is the most a description needs, and four times the tables' worth of
// values (entries may overlap) the most it keeps.
class InitBudget {
  public:
    static constexpr std::uint64_t kMaxValues = 4ull * 4 * kFullTable;
    static constexpr std::uint64_t kMaxWrites = 4ull * kFullTable * 256;

    void charge(const Parser& p, const YAML::Node& entry, std::size_t index, const InitRange& r,
                const Layout& layout) {
        const std::uint64_t models =
            layout.shared ? 1 : (r.units.empty() ? layout.units.size() : r.units.size());
        values_ += r.words.size();
        writes_ += r.words.size() * models;
        if (values_ > kMaxValues)
            p.fail(entry, "init entry " + std::to_string(index + 1) + ": init holds more than " +
                              std::to_string(kMaxValues) +
                              " values in all (an alias counts each time it is used)");
        if (writes_ > kMaxWrites)
            p.fail(entry, "init entry " + std::to_string(index + 1) + ": init writes more than " +
                              std::to_string(kMaxWrites) +
                              " values in all, each unit an entry applies to counted (every "
                              "register of every unit once)");
    }

  private:
    std::uint64_t values_ = 0;
    std::uint64_t writes_ = 0;
};

void parse_init(const Parser& p, const YAML::Node& list, const Layout& layout,
                std::vector<InitRange>& out) {
    if (!list.IsSequence()) p.fail(list, "init must be a list");
    InitBudget budget;
    for (const auto& e : list) {
        InitRange r;
        OptNode table, address, values, value, count, random, type;
        p.each_key(e, "init entry",
                   {"table", "address", "values", "value", "count", "random", "type", "units"},
                   [&](const std::string& key, const YAML::Node& v) {
                       if (key == "table")
                           table.emplace(v);
                       else if (key == "address")
                           address.emplace(v);
                       else if (key == "values")
                           values.emplace(v);
                       else if (key == "value")
                           value.emplace(v);
                       else if (key == "count")
                           count.emplace(v);
                       else if (key == "random")
                           random.emplace(v);
                       else if (key == "type")
                           type.emplace(v);
                       else if (key == "units")
                           r.units = parse_entry_units(p, v, layout);
                       else
                           return false;
                       return true;
                   });
        if (!table) p.fail(e, "init entry needs 'table'");
        if (!address) p.fail(e, "init entry needs 'address'");
        r.table = parse_table(p, *table);
        r.address = p.address(*address, r.table);
        const ValueType vt = type ? parse_type(p, *type) : ValueType::UInt16;
        if (type && is_bit_table(r.table)) p.fail(*type, "bit tables take no 'type'");
        const int sources = (values ? 1 : 0) + (value ? 1 : 0) + (random ? 1 : 0);
        if (sources != 1) p.fail(e, "init entry needs exactly one of 'values', 'value', 'random'");
        if (count && values) p.fail(*count, "'count' goes with 'value' or 'random', not 'values'");
        const auto n = count ? p.integer(*count, "count", 1, 65536) : 1;
        if (values) {
            if (!values->IsSequence()) p.fail(*values, "'values' must be a list");
            for (const auto& v : *values) push_value(p, v, r.table, vt, r.words);
        } else if (value) {
            std::vector<std::uint16_t> one;
            push_value(p, *value, r.table, vt, one);
            for (std::int64_t i = 0; i < n; ++i)
                r.words.insert(r.words.end(), one.begin(), one.end());
        } else {
            push_random_words(p, *random, vt, n, r);
        }
        check_fits(p, e, layout, r.table, r.address, r.words.size());
        budget.charge(p, e, out.size(), r, layout);
        out.push_back(std::move(r));
    }
}

void parse_counters(const Parser& p, const YAML::Node& list, const Layout& layout,
                    DeviceDescription& d) {
    if (!list.IsSequence()) p.fail(list, "counters must be a list");
    for (const auto& e : list) {
        OptNode table, address, mode, step, start, interval, type;
        std::vector<std::uint8_t> units;
        p.each_key(e, "counter",
                   {"table", "address", "mode", "step", "start", "interval_ms", "type", "units"},
                   [&](const std::string& key, const YAML::Node& v) {
                       if (key == "table")
                           table.emplace(v);
                       else if (key == "address")
                           address.emplace(v);
                       else if (key == "mode")
                           mode.emplace(v);
                       else if (key == "step")
                           step.emplace(v);
                       else if (key == "start")
                           start.emplace(v);
                       else if (key == "interval_ms")
                           interval.emplace(v);
                       else if (key == "type")
                           type.emplace(v);
                       else if (key == "units")
                           units = parse_entry_units(p, v, layout);
                       else
                           return false;
                       return true;
                   });
        if (!address) p.fail(e, "counter needs 'address'");
        const Table t = table ? parse_table(p, *table) : Table::InputRegisters;
        if (is_bit_table(t))
            p.fail(*table, "counters live in input_registers or holding_registers");
        const auto addr = p.address(*address, t);
        const std::string m = mode ? p.scalar(*mode, "mode") : std::string("read");
        if (m == "read") {
            if (interval) p.fail(*interval, "'interval_ms' needs mode: interval");
            if (type) p.fail(*type, "read counters are plain 16-bit registers (no 'type')");
            check_fits(p, e, layout, t, addr, 1);
            ReadCounterSpec c;
            c.table = t;
            c.address = addr;
            c.step = static_cast<std::uint16_t>(step ? p.integer(*step, "step", -65535, 65535) : 1);
            c.start =
                static_cast<std::uint16_t>(start ? p.integer(*start, "start", -32768, 65535) : 0);
            c.units = std::move(units);
            d.read_counters.push_back(std::move(c));
        } else if (m == "interval") {
            if (!interval) p.fail(e, "mode: interval needs 'interval_ms'");
            SimulatedInput s;
            s.table = t;
            s.address = addr;
            s.wave = Waveform::Counter;
            s.type = type ? parse_type(p, *type) : ValueType::UInt16;
            s.period_ns = p.millis(*interval, "interval_ms");
            if (s.period_ns == 0) p.fail(*interval, "interval_ms must be above 0");
            s.step = step ? p.number(*step, "step") : 1.0;
            s.offset = start ? p.number(*start, "start") : 0.0;
            s.units = std::move(units);
            check_fits(p, e, layout, t, addr, value_width(s.type));
            d.simulated.push_back(std::move(s));
        } else {
            p.fail(*mode, "counter mode must be 'read' or 'interval'");
        }
    }
}

void parse_simulate(const Parser& p, const YAML::Node& list, const Layout& layout,
                    std::vector<SimulatedInput>& out) {
    if (!list.IsSequence()) p.fail(list, "simulate must be a list");
    for (const auto& e : list) {
        SimulatedInput s;
        OptNode table, address, wave, period, type;
        p.each_key(e, "simulated input",
                   {"table", "address", "wave", "period_ms", "type", "amplitude", "offset", "phase",
                    "duty", "min", "max", "seed", "units"},
                   [&](const std::string& key, const YAML::Node& v) {
                       if (key == "table")
                           table.emplace(v);
                       else if (key == "address")
                           address.emplace(v);
                       else if (key == "wave")
                           wave.emplace(v);
                       else if (key == "period_ms")
                           period.emplace(v);
                       else if (key == "type")
                           type.emplace(v);
                       else if (key == "amplitude")
                           s.amplitude = p.number(v, key);
                       else if (key == "offset")
                           s.offset = p.number(v, key);
                       else if (key == "phase")
                           s.phase = p.number(v, key);
                       else if (key == "duty")
                           s.duty = p.rate(v, key);
                       else if (key == "min")
                           s.min = p.number(v, key);
                       else if (key == "max")
                           s.max = p.number(v, key);
                       else if (key == "seed")
                           s.seed = static_cast<std::uint64_t>(p.integer(v, key, 0, INT64_MAX));
                       else if (key == "units")
                           s.units = parse_entry_units(p, v, layout);
                       else
                           return false;
                       return true;
                   });
        if (!table) p.fail(e, "simulated input needs 'table'");
        if (!address) p.fail(e, "simulated input needs 'address'");
        if (!wave) p.fail(e, "simulated input needs 'wave'");
        if (!period) p.fail(e, "simulated input needs 'period_ms'");
        s.table = parse_table(p, *table);
        s.address = p.address(*address, s.table);
        const std::string w = p.scalar(*wave, "wave");
        if (w == "ramp")
            s.wave = Waveform::Ramp;
        else if (w == "sine")
            s.wave = Waveform::Sine;
        else if (w == "square")
            s.wave = Waveform::Square;
        else if (w == "random")
            s.wave = Waveform::Random;
        else
            p.fail(*wave, "unknown wave '" + w + "' (ramp, sine, square or random)");
        s.period_ns = p.millis(*period, "period_ms");
        if (s.period_ns == 0) p.fail(*period, "period_ms must be above 0");
        if (type) {
            if (is_bit_table(s.table)) p.fail(*type, "bit tables take no 'type'");
            s.type = parse_type(p, *type);
        }
        if (s.wave == Waveform::Random && s.min > s.max) p.fail(e, "min must not exceed max");
        check_fits(p, e, layout, s.table, s.address, value_width(s.type));
        out.push_back(std::move(s));
    }
}

void parse_faults(const Parser& p, const YAML::Node& n, FaultConfig& f) {
    p.each_key(
        n, "faults", {"delay", "stall", "exception", "drop_rate", "no_answer_rate", "seed"},
        [&](const std::string& key, const YAML::Node& v) {
            if (key == "delay") {
                // `none` is the default written out (what --print-scenario shows).
                if (v.IsScalar() && v.Scalar() == "none") {
                    f.delay = DelayConfig{};
                    return true;
                }
                int kinds = 0;
                p.each_key(v, "faults.delay", {"fixed_ms", "uniform_ms", "exponential_mean_ms"},
                           [&](const std::string& k, const YAML::Node& x) {
                               ++kinds;
                               if (k == "fixed_ms") {
                                   f.delay.kind = DelayConfig::Kind::Fixed;
                                   f.delay.fixed_ns = p.millis(x, k);
                               } else if (k == "uniform_ms") {
                                   if (!x.IsSequence() || x.size() != 2)
                                       p.fail(x, "uniform_ms must be [min, max]");
                                   f.delay.kind = DelayConfig::Kind::Uniform;
                                   f.delay.min_ns = p.millis(x[0], "uniform_ms min");
                                   f.delay.max_ns = p.millis(x[1], "uniform_ms max");
                                   if (f.delay.min_ns > f.delay.max_ns)
                                       p.fail(x, "uniform_ms needs min <= max");
                               } else if (k == "exponential_mean_ms") {
                                   f.delay.kind = DelayConfig::Kind::Exponential;
                                   f.delay.mean_ns = p.millis(x, k);
                               } else {
                                   return false;
                               }
                               return true;
                           });
                if (kinds != 1)
                    p.fail(
                        v,
                        "delay needs exactly one of fixed_ms, uniform_ms, exponential_mean_ms (or "
                        "delay: none)");
            } else if (key == "stall") {
                p.each_key(v, "faults.stall", {"duration_ms", "every_ms"},
                           [&](const std::string& k, const YAML::Node& x) {
                               if (k == "duration_ms")
                                   f.stall.duration_ns = p.millis(x, k);
                               else if (k == "every_ms")
                                   f.stall.period_ns = p.millis(x, k);
                               else
                                   return false;
                               return true;
                           });
            } else if (key == "exception") {
                p.each_key(v, "faults.exception", {"rate", "code"},
                           [&](const std::string& k, const YAML::Node& x) {
                               if (k == "rate")
                                   f.exception_rate = p.rate(x, "exception rate");
                               else if (k == "code")
                                   f.exception_code = static_cast<codec::ExceptionCode>(
                                       p.integer(x, "exception code", 1, 127));
                               else
                                   return false;
                               return true;
                           });
            } else if (key == "drop_rate") {
                f.drop_rate = p.rate(v, key);
            } else if (key == "no_answer_rate") {
                f.no_answer_rate = p.rate(v, key);
            } else if (key == "seed") {
                f.seed = static_cast<std::uint64_t>(p.integer(v, key, 0, INT64_MAX));
            } else {
                return false;
            }
            return true;
        });
    if (const Error problem = validate(f); !problem.ok()) p.fail(n, problem.message());
}

// `tls_roles: {Operator: "1-6,15,16", Viewer: [1, 2, 3, 4]}`: a list per role, read by the
// codec's one parser of function code lists (serve --tls-role uses it too).
void parse_tls_roles(const Parser& p, const YAML::Node& n, DeviceDescription& d) {
    if (!n.IsMap())
        p.fail(n,
               "tls_roles maps each role to the function codes it may use, e.g. "
               "{Operator: \"1-6,15,16\", Viewer: \"1-4\"}");
    for (const auto& kv : n) {
        const std::string role = p.scalar(kv.first, "role");
        if (role.empty()) p.fail(kv.first, "tls_roles: an empty role name");
        for (const auto& [known, set] : d.tls_roles)
            if (known == role) p.fail(kv.first, "tls_roles: role '" + role + "' given twice");
        std::string list;
        if (kv.second.IsSequence()) {
            for (const auto& item : kv.second)
                list += (list.empty() ? "" : ",") + p.scalar(item, "function code");
        } else {
            list = p.scalar(kv.second, "function codes");
        }
        codec::FunctionSet set;
        if (const std::string why = codec::parse_function_set(list, set); !why.empty())
            p.fail(kv.second, "tls_roles." + role + ": " + why);
        d.tls_roles.emplace_back(role, set);
    }
}

DeviceDescription parse_document(const Parser& p, const YAML::Node& root) {
    DeviceDescription d;
    if (root.IsNull()) return d;  // an empty document is the default device
    std::map<std::string, YAML::Node> keys;
    static constexpr std::string_view kKnown[] = {"tables",
                                                  "units",
                                                  "unknown_unit",
                                                  "broadcast_unit_zero",
                                                  "diagnostics",
                                                  "files",
                                                  "exception_status",
                                                  "server_id",
                                                  "run_indicator",
                                                  "identification",
                                                  "init",
                                                  "counters",
                                                  "simulate",
                                                  "faults",
                                                  "tls_roles"};
    p.each_key(root, "device description", kKnown,
               [&](const std::string& key, const YAML::Node& v) {
                   keys[key] = v;
                   return true;
               });
    auto has = [&](const char* k) { return keys.count(k) != 0; };

    Layout layout;
    if (has("tables")) parse_tables(p, keys["tables"], d.model.sizes);
    layout.sizes = d.model.sizes;
    if (has("units")) {
        const YAML::Node& u = keys["units"];
        if (u.IsScalar() && u.Scalar() == "shared") {
            d.shared = true;
        } else {
            d.shared = false;
            d.units = parse_unit_list(p, u);
            std::sort(d.units.begin(), d.units.end());
            d.units.erase(std::unique(d.units.begin(), d.units.end()), d.units.end());
        }
    }
    layout.shared = d.shared;
    layout.units = d.units;
    if (has("unknown_unit")) {
        const YAML::Node& n = keys["unknown_unit"];
        const std::string s = p.scalar(n, "unknown_unit");
        if (s == "gateway_target_failed")
            d.unknown_unit = UnknownUnitPolicy::GatewayTargetFailed;
        else if (s == "gateway_path_unavailable")
            d.unknown_unit = UnknownUnitPolicy::GatewayPathUnavailable;
        else if (s == "ignore")
            d.unknown_unit = UnknownUnitPolicy::Ignore;
        else
            p.fail(
                n,
                "unknown_unit must be gateway_target_failed, gateway_path_unavailable or ignore");
    }
    if (has("broadcast_unit_zero"))
        d.broadcast_unit_zero = p.boolean(keys["broadcast_unit_zero"], "broadcast_unit_zero");
    if (has("diagnostics"))
        d.model.track_diagnostics = p.boolean(keys["diagnostics"], "diagnostics");
    if (has("files")) parse_files(p, keys["files"], d.model);
    if (has("exception_status")) {
        d.model.exception_status = static_cast<std::uint8_t>(
            p.integer(keys["exception_status"], "exception_status", 0, 255));
    }
    if (has("server_id")) {
        const YAML::Node& n = keys["server_id"];
        d.model.server_id.clear();
        if (n.IsSequence()) {
            for (const auto& b : n)
                d.model.server_id.push_back(
                    static_cast<std::uint8_t>(p.integer(b, "server_id byte", 0, 255)));
        } else {
            const std::string s = p.scalar(n, "server_id");
            d.model.server_id.assign(s.begin(), s.end());
        }
        if (d.model.server_id.size() > 250) p.fail(n, "server_id longer than 250 bytes");
    }
    if (has("run_indicator"))
        d.model.run_indicator_on = p.boolean(keys["run_indicator"], "run_indicator");
    if (has("identification")) parse_identification(p, keys["identification"], d.model.identity);
    if (has("init")) parse_init(p, keys["init"], layout, d.init);
    if (has("counters")) parse_counters(p, keys["counters"], layout, d);
    if (has("simulate")) parse_simulate(p, keys["simulate"], layout, d.simulated);
    if (has("faults")) parse_faults(p, keys["faults"], d.faults);
    if (has("tls_roles")) parse_tls_roles(p, keys["tls_roles"], d);
    return d;
}

}  // namespace

DeviceDescription parse_device_node(const YAML::Node& node, std::string_view source) {
    const Parser p(source);
    try {
        return parse_document(p, node);
    } catch (const YAML::Exception& e) {  // e.g. a mapping where a scalar was expected
        p.fail(e.mark, e.msg);
    }
}

std::span<const IdentificationKey> identification_keys() noexcept {
    static constexpr IdentificationKey kKeys[] = {
        {"vendor_name", DeviceIdentity::kVendorName},
        {"product_code", DeviceIdentity::kProductCode},
        {"major_minor_revision", DeviceIdentity::kMajorMinorRevision},
        {"vendor_url", DeviceIdentity::kVendorUrl},
        {"product_name", DeviceIdentity::kProductName},
        {"model_name", DeviceIdentity::kModelName},
        {"user_application_name", DeviceIdentity::kUserApplicationName},
    };
    return kKeys;
}

Result<DeviceDescription> parse_device_yaml(std::string_view text, std::string_view source) {
    // The slave layer's edge: yaml-cpp's exceptions and the reader's DeviceYamlError stop here.
    try {
        const Parser p(source);
        YAML::Node root;
        try {
            root = YAML::Load(std::string(text));
        } catch (const YAML::Exception& e) {
            p.fail(e.mark, e.msg);
        }
        return parse_device_node(root, source);
    } catch (const DeviceYamlError& e) {
        return Error(ErrorCode::InvalidInput, e.what());
    }
}

Result<DeviceDescription> load_device_file(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return Error(ErrorCode::Io, path + ": cannot open the device file");
    // Every table written out value by value is about 2 MB of YAML: a file far larger is not a
    // device description, and is not read into memory whole.
    constexpr std::size_t kMaxBytes = 16u << 20;
    std::string text;
    char chunk[1 << 16];
    while (text.size() <= kMaxBytes && in.read(chunk, sizeof chunk).gcount() > 0)
        text.append(chunk, static_cast<std::size_t>(in.gcount()));
    if (text.size() > kMaxBytes)
        return Error(ErrorCode::InvalidInput,
                     path + ": larger than 16 MiB: not a device description");
    return parse_device_yaml(text, path);
}

UnitModels build_units(const DeviceDescription& d) {
    UnitModels units =
        d.shared ? UnitModels::shared(d.model) : UnitModels::per_unit(d.model, d.units);
    units.unknown_unit_policy = d.unknown_unit;
    units.broadcast_unit_zero = d.broadcast_unit_zero;
    auto for_models = [&](const std::vector<std::uint8_t>& filter, auto&& f) {
        if (filter.empty() || units.is_shared()) {
            for (std::size_t i = 0; i < units.model_count(); ++i) f(units.model_at(i));
        } else {
            for (std::uint8_t u : filter) {
                if (DataModel* m = units.find(u)) f(*m);
            }
        }
    };
    for (const InitRange& r : d.init) {
        for_models(r.units, [&](DataModel& m) {
            for (std::size_t i = 0; i < r.words.size(); ++i) {
                const auto a = static_cast<std::uint16_t>(r.address + i);
                switch (r.table) {
                    case Table::Coils:
                        m.coils().set(a, r.words[i] != 0);
                        break;
                    case Table::DiscreteInputs:
                        m.discrete_inputs().set(a, r.words[i] != 0);
                        break;
                    case Table::InputRegisters:
                        m.input_registers().set(a, r.words[i]);
                        break;
                    case Table::HoldingRegisters:
                        m.holding_registers().set(a, r.words[i]);
                        break;
                }
            }
        });
    }
    for (const ReadCounterSpec& c : d.read_counters) {
        for_models(c.units, [&](DataModel& m) {
            RegisterTable& t =
                c.table == Table::InputRegisters ? m.input_registers() : m.holding_registers();
            t.set(c.address, c.start);
            t.add_read_counter(c.address, c.step);
        });
    }
    return units;
}

}  // namespace mbstorm::slave
