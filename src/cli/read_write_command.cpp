// `mbstorm read` and `mbstorm write`: one range, once or every --interval, values typed as
// asked. Two commands rather than one `poll`: a write changes a device, and its name on the
// command line says so (and it alone takes --allow-writes).
#include <fmt/format.h>
#include <time.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "cli/commands.hpp"
#include "cli/deprecated_option.hpp"
#include "cli/duration_option.hpp"
#include "cli/frame_describe.hpp"
#include "cli/modbus_client.hpp"
#include "cli/transport_options.hpp"
#include "cli/typed_values.hpp"
#include "codec/address.hpp"
#include "codec/exception_code.hpp"
#include "codec/function_code.hpp"
#include "codec/limits.hpp"
#include "codec/pdu.hpp"
#include "load/plan.hpp"
#include "load/preflight.hpp"
#include "load/serial_master.hpp"
#include "load/write_safety.hpp"
#include "net/socket.hpp"

namespace mbstorm::cli {
namespace {

// "0x05 write_single_coil (one value) or 0x0F write_multiple_coils": the writes of a table.
std::string write_choices(codec::Table table) {
    const bool bits = codec::is_bit_table(table);
    const auto single =
        bits ? codec::RequestShape::SingleCoil : codec::RequestShape::SingleRegister;
    const auto multiple =
        bits ? codec::RequestShape::MultipleCoils : codec::RequestShape::MultipleRegisters;
    return fmt::format("{} (one value) or {}",
                       codec::function_label(codec::function_for(table, single)),
                       codec::function_label(codec::function_for(table, multiple)));
}

struct IoOptions {
    bool write = false;
    std::string target;
    int unit = 1;
    std::string address = "0";
    std::string table;
    std::string type;
    std::string order = "ABCD";
    int quantity = 1;             // read: values of --type
    bool quantity_given = false;  // --quantity on the command line (a range gives it too)
    std::vector<std::string> values;
    std::string function;            // write: force 05/06/0F/10
    std::uint64_t transactions = 1;  // 0: until interrupted
    std::uint64_t interval_ns = 1'000'000'000ULL;
    std::uint64_t timeout_ns = 1'000'000'000ULL;
    bool json = false;
    bool allow_writes = false;
    // read: each value also (text: only) as its registers in hex, as they came
    bool hex = false;
    bool one_based = false;   // read: [1] is address 0, as mbpoll shows it
    bool timestamps = false;  // each transaction's time, UTC (JSON: "time")
    TransportOptions transport;
};

// What the options resolve to before anything is sent.
struct IoPlan {
    net::Endpoint target;
    std::string peer;  // what the messages name: HOST:PORT or the tty
    codec::Table table = codec::Table::HoldingRegisters;
    std::uint16_t address = 0;
    ValueType type = ValueType::U16;
    codec::WordOrder order = codec::WordOrder::ABCD;
    codec::Request request;
    std::vector<std::uint8_t> payload;     // write data the request points at
    std::vector<std::uint16_t> registers;  // write: the registers (or bits) written
    std::uint16_t items = 0;               // registers or bits read or written
    std::uint32_t range_items = 0;         // read --addr FIRST-LAST: registers or bits in it
};

bool table_from_text(const std::string& text, codec::Table& out) {
    if (codec::table_from_name(text, out)) return true;
    static constexpr std::pair<std::string_view, codec::Table> kShort[] = {
        {"coil", codec::Table::Coils},
        {"discrete", codec::Table::DiscreteInputs},
        {"input", codec::Table::InputRegisters},
        {"holding", codec::Table::HoldingRegisters}};
    for (auto [name, table] : kShort) {
        if (text == name) {
            out = table;
            return true;
        }
    }
    return false;
}

// A read: the items --quantity values of --type take, or those of a range --addr.
std::string read_request(const IoOptions& o, IoPlan& p, bool bit_table) {
    auto& r = p.request;
    r.function = codec::function_for(p.table, codec::RequestShape::AddressQuantity);
    std::size_t items = bit_table ? static_cast<std::size_t>(o.quantity)
                        : p.type == ValueType::String
                            ? (static_cast<std::size_t>(o.quantity) + 1) / 2
                            : static_cast<std::size_t>(o.quantity) * registers_per_value(p.type);
    // A range is the registers (or bits) read: whole values of --type only.
    if (p.range_items != 0) {
        const std::size_t per =
            bit_table || p.type == ValueType::String ? 1 : registers_per_value(p.type);
        if (p.range_items % per != 0)
            return fmt::format(
                "--addr '{}' holds {} registers, not a whole number of {} "
                "values ({} registers each)",
                o.address, p.range_items, o.type, per);
        items = p.range_items;
    }
    if (items > 0xFFFF) items = 0xFFFF;
    r.quantity = static_cast<std::uint16_t>(items);
    p.items = r.quantity;
    return {};
}

// The table (--table, or the reference number's, or holding registers) and the address, or
// the range to read.
std::string resolve_address(const IoOptions& o, IoPlan& p) {
    // The table: --table, or the reference number's, or holding registers.
    std::optional<codec::Table> table;
    if (!o.table.empty()) {
        codec::Table t;
        if (!table_from_text(o.table, t))
            return fmt::format(
                "--table '{}': valid coils, discrete_inputs, input_registers, holding_registers "
                "(or coil, discrete, input, holding)",
                o.table);
        table = t;
    }
    if (codec::Reference ref; !table && codec::parse_reference(o.address, ref)) table = ref.table;
    p.table = table.value_or(codec::Table::HoldingRegisters);
    codec::AddressRange range;
    if (auto error = codec::parse_address_range(o.address, p.table, range); !error.empty())
        return "--addr " + error;
    p.address = range.first;
    p.range_items = range.is_range ? range.last - range.first + 1 : 0;
    if (range.is_range && o.write)
        return fmt::format(
            "--addr '{}' is a range: give the first address (the values say how "
            "many are written)",
            o.address);
    if (range.is_range && o.quantity_given)
        return fmt::format("--addr '{}' is a range: it says how many to read, without --quantity",
                           o.address);
    return {};
}

std::string build_request(const IoOptions& o, IoPlan& p) {
    if (std::string e = resolve_address(o, p); !e.empty()) return e;

    const bool bit_table = codec::is_bit_table(p.table);
    if (!o.type.empty() && !value_type_from_name(o.type, p.type))
        return fmt::format("--type '{}': valid {}", o.type, kValueTypeNames);
    if (bit_table && o.hex)
        return fmt::format("--hex shows registers in hex; {} hold single bits",
                           codec::table_name(p.table));
    if (bit_table) {
        if (!o.type.empty() && p.type != ValueType::Bits)
            return fmt::format("--type {}: {} hold single bits; use --type bits (the default)",
                               o.type, codec::table_name(p.table));
        p.type = ValueType::Bits;
    }
    if (!codec::word_order_from_name(o.order, p.order))
        return fmt::format("--order '{}': valid ABCD, CDAB, BADC, DCBA", o.order);

    auto& r = p.request;
    r.address = p.address;
    if (!o.write) return read_request(o, p, bit_table);

    if (p.table == codec::Table::InputRegisters || p.table == codec::Table::DiscreteInputs)
        return fmt::format("{} are read-only: {}", codec::table_name(p.table),
                           codec::table_functions(p.table));
    if (o.values.empty()) return "give the values to write after the options";
    if (bit_table) {
        for (const auto& v : o.values) {
            bool bit = false;
            if (!parse_bit(v, bit))
                return fmt::format("value '{}': a coil takes 1/0, on/off or true/false", v);
            p.registers.push_back(bit ? 1 : 0);
        }
    } else if (const Error error = registers_from_text(o.values, p.type, p.order, p.registers);
               !error.ok()) {
        return error.text();
    }
    if (p.registers.size() > 0xFFFF) return "too many values";
    p.items = static_cast<std::uint16_t>(p.registers.size());
    const bool one = p.registers.size() == 1;
    const auto single =
        bit_table ? codec::RequestShape::SingleCoil : codec::RequestShape::SingleRegister;
    const auto multiple =
        bit_table ? codec::RequestShape::MultipleCoils : codec::RequestShape::MultipleRegisters;
    r.function = codec::function_for(p.table, one ? single : multiple);
    if (!o.function.empty()) {
        std::uint8_t fc = 0;
        if (auto error = codec::parse_function_code(o.function, fc); !error.empty())
            return "--fc: " + error;
        const bool fits = fc == codec::function_for(p.table, multiple) ||
                          (one && fc == codec::function_for(p.table, single));
        if (!fits)
            return fmt::format("--fc '{}' cannot write {} value(s) to {}: valid {}", o.function,
                               p.registers.size(), codec::table_name(p.table),
                               write_choices(p.table));
        r.function = fc;
    }
    switch (codec::function_info(r.function)->request) {
        case codec::RequestShape::SingleCoil:
            r.value = p.registers[0] ? codec::limits::kCoilOn : codec::limits::kCoilOff;
            break;
        case codec::RequestShape::SingleRegister:
            r.value = p.registers[0];
            break;
        case codec::RequestShape::MultipleCoils: {
            std::vector<std::uint8_t> bits(p.registers.begin(), p.registers.end());
            p.payload.assign(codec::packed_bit_bytes(bits.size()), 0);
            codec::pack_bit_bytes(bits, p.payload);
            r.quantity = p.items;
            break;
        }
        case codec::RequestShape::MultipleRegisters:
            for (std::uint16_t w : p.registers) {
                p.payload.push_back(static_cast<std::uint8_t>(w >> 8));
                p.payload.push_back(static_cast<std::uint8_t>(w & 0xFF));
            }
            r.quantity = p.items;
            break;
        case codec::RequestShape::FunctionOnly:
        case codec::RequestShape::AddressQuantity:
        case codec::RequestShape::SubFunction:
        case codec::RequestShape::FileRecords:
        case codec::RequestShape::MaskWrite:
        case codec::RequestShape::ReadWriteRegisters:
        case codec::RequestShape::FifoPointer:
        case codec::RequestShape::MeiTransport:
            // function_for and --fc above pick only the four shapes of plain writes.
            return fmt::format("{} does not write values as given here",
                               codec::function_label(r.function));
    }
    return {};
}

// Now, UTC, to the millisecond: "2026-11-28T10:15:02.317Z".
std::string utc_now() {
    const auto now = std::chrono::system_clock::now();
    const std::time_t seconds = std::chrono::system_clock::to_time_t(now);
    const auto ms =
        std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count() %
        1000;
    std::tm utc{};
    ::gmtime_r(&seconds, &utc);
    return fmt::format("{:04}-{:02}-{:02}T{:02}:{:02}:{:02}.{:03}Z", utc.tm_year + 1900,
                       utc.tm_mon + 1, utc.tm_mday, utc.tm_hour, utc.tm_min, utc.tm_sec, ms);
}

// The registers of value `v` (read from `first`), in hex as they came: "0x4060" or
// "0x40600000".
std::string hex_of(const TypedValue& v, const std::vector<std::uint16_t>& regs, std::uint16_t first,
                   std::size_t per_value) {
    std::string out = "0x";
    const std::size_t from = static_cast<std::uint16_t>(v.address - first);
    for (std::size_t i = from; i < regs.size() && i < from + per_value; ++i)
        out += fmt::format("{:04X}", regs[i]);
    return out;
}

// A read's values: one line each ("[100]: 3.5"), or one JSON object each.
void print_values(const IoOptions& o, const IoPlan& p, const std::vector<TypedValue>& values,
                  const std::vector<std::uint16_t>& regs, nlohmann::json* json) {
    // A string is one value over every register read.
    const std::size_t per_value =
        p.type == ValueType::String ? regs.size() : registers_per_value(p.type);
    for (const auto& v : values) {
        const std::string hex = o.hex ? hex_of(v, regs, p.address, per_value) : "";
        const unsigned label = v.address + (o.one_based ? 1u : 0u);
        if (!json) {
            fmt::print("[{}]: {}{}\n", label, v.text, o.hex ? " " + hex : "");
            continue;
        }
        nlohmann::json item{{"address", v.address}};
        if (o.one_based) item["reference"] = label;
        const bool floating = p.type == ValueType::F32 || p.type == ValueType::F64;
        if (!v.is_number)
            item["value"] = v.text;
        else if (floating)
            item["value"] = v.number;
        else
            item["value"] = nlohmann::json::parse(v.text);  // integers exactly, not via double
        if (o.hex) item["hex"] = hex;
        json->push_back(item);
    }
}

// One transaction's outcome, printed as text or one JSON line.
int report(const IoOptions& o, const IoPlan& p, std::uint64_t poll, const std::string& error,
           const codec::Response& rsp) {
    nlohmann::json j;
    if (o.json) {
        j["target"] = p.peer;
        j["unit"] = o.unit;
        j["function"] = codec::function_label(p.request.function);
        j["table"] = std::string(codec::table_name(p.table));
        j["address"] = p.address;
        if (o.transactions != 1) j["poll"] = poll;
        if (o.timestamps) j["time"] = utc_now();
    } else if (o.timestamps) {
        if (poll > 1) fmt::print("\n");
        fmt::print("-- {} poll {}\n", utc_now(), poll);
    }
    auto emit_json = [&] { fmt::print("{}\n", j.dump()); };
    if (!error.empty()) {
        if (o.json) {
            j["error"] = error;
            emit_json();
        }
        fmt::print(stderr, "mbstorm {}: {} ({} to unit {} at {}): {}\n", o.write ? "write" : "read",
                   p.peer, codec::function_label(p.request.function), o.unit, p.address, error);
        return kExitFailed;
    }
    if (rsp.exception != codec::ExceptionCode::None) {
        const auto code = static_cast<int>(rsp.exception);
        if (o.json) {
            j["exception"] = {{"code", code},
                              {"name", std::string(codec::exception_name(rsp.exception))}};
            emit_json();
        }
        fmt::print(stderr, "mbstorm {}: unit {} answered exception {:02X} {} to {} at address {}\n",
                   o.write ? "write" : "read", o.unit, code, codec::exception_name(rsp.exception),
                   codec::function_label(p.request.function), p.address);
        return kExitFailed;
    }
    if (o.write) {
        if (o.json) {
            j["written"] = p.registers;
            j["type"] = std::string(value_type_name(p.type));
            j["order"] = std::string(codec::word_order_name(p.order));
            emit_json();
        } else {
            fmt::print("wrote {} {} at address {} of unit {} ({})\n", p.items,
                       codec::is_bit_table(p.table) ? "bit(s)" : "register(s)", p.address, o.unit,
                       codec::function_label(p.request.function));
        }
        return kExitOk;
    }
    std::vector<TypedValue> values;
    std::vector<std::uint16_t> regs;
    if (codec::is_bit_table(p.table)) {
        for (std::uint16_t i = 0; i < p.items && i / 8u < rsp.payload.size(); ++i) {
            const bool bit = codec::bit_at(rsp.payload, i);
            regs.push_back(bit);
            values.push_back({static_cast<std::uint16_t>(p.address + i), bit ? "1" : "0",
                              bit ? 1.0 : 0.0, true});
        }
    } else {
        for (std::size_t i = 0; i + 1 < rsp.payload.size(); i += 2)
            regs.push_back(codec::load_be16(rsp.payload.data() + i));
        values = values_from_registers(regs, p.address, p.type, p.order);
    }
    if (o.json) {
        j["type"] = std::string(value_type_name(p.type));
        j["order"] = std::string(codec::word_order_name(p.order));
        j["registers"] = regs;
        print_values(o, p, values, regs, &(j["values"] = nlohmann::json::array()));
        emit_json();
    } else {
        if (o.transactions != 1 && poll > 1 && !o.timestamps) fmt::print("\n");
        print_values(o, p, values, regs, nullptr);
    }
    std::fflush(stdout);
    return kExitOk;
}

// read/write --serial: the same request and report, one transaction on the line at a time.
int run_serial_io(const IoOptions& o, IoPlan& p,
                  const std::array<std::uint8_t, codec::limits::kMaxPdu>& pdu,
                  std::size_t pdu_size) {
    const char* name = o.write ? "write" : "read";
    const auto& device = o.transport.serial_device;
    p.peer = device;
    if (!o.target.empty()) return usage_error(name, "--target and --serial exclude each other");
    if (o.write && !o.allow_writes && !net::is_pseudo_terminal(device))
        return usage_error(name,
                           fmt::format("{} is a real serial line: writing to the devices on it "
                                       "needs --allow-writes",
                                       device));
    load::SerialMaster master;
    if (Error why = master.open(device, serial_settings(o.transport), o.transport.framing_kind());
        !why.ok())
        return usage_error(name, why.text());
    int exit_code = kExitOk;
    const auto interval = std::chrono::nanoseconds(o.interval_ns);
    auto next = std::chrono::steady_clock::now();
    for (std::uint64_t poll = 1; o.transactions == 0 || poll <= o.transactions; ++poll) {
        codec::Response rsp;
        codec::Bytes answer;
        std::int64_t sent_ns = 0;
        const auto outcome =
            master.transact(static_cast<std::uint8_t>(o.unit), codec::Bytes(pdu.data(), pdu_size),
                            static_cast<std::int64_t>(o.timeout_ns), answer, sent_ns);
        std::string why;
        switch (outcome) {
            case load::SerialOutcome::Answered:
                if (auto err = codec::decode_response(answer, rsp); err != codec::CodecError::Ok)
                    why = fmt::format("malformed answer ({}): {}", codec::format_hex(answer),
                                      codec::error_description(err));
                break;
            case load::SerialOutcome::Broadcast:
                break;  // nothing comes back: report() prints what was sent
            case load::SerialOutcome::Timeout:
                why = fmt::format("no answer within {} ms", o.timeout_ns / 1'000'000);
                break;
            case load::SerialOutcome::BadCheck:
                why = o.transport.framing == "ascii" ? "the answer's LRC is wrong"
                                                     : "the answer's CRC is wrong";
                break;
            case load::SerialOutcome::BadFrame:
                why = "the answer was a broken frame";
                break;
            case load::SerialOutcome::WrongUnit:
                why = "the answer came from another unit";
                break;
            case load::SerialOutcome::IoError:
                why = fmt::format("{}: {}", device, std::strerror(master.io_error()));
                break;
        }
        if (report(o, p, poll, why, rsp) != kExitOk) exit_code = kExitFailed;
        if (outcome == load::SerialOutcome::IoError) break;
        if (o.transactions != 0 && poll == o.transactions) break;
        next += interval;
        std::this_thread::sleep_until(next);
    }
    return exit_code;
}

int run_io(const IoOptions& o) {
    const char* name = o.write ? "write" : "read";
    auto usage = [name](std::string_view message) { return usage_error(name, message); };
    if (const Error e = check_transport(o.transport, name); !e.ok()) return fail(name, e);
    IoPlan p;
    if (auto error = build_request(o, p); !error.empty()) return usage(error);
    p.request.payload = codec::Bytes(p.payload.data(), p.payload.size());
    std::array<std::uint8_t, codec::limits::kMaxPdu> pdu{};
    auto enc = codec::encode_request(p.request, pdu, /*allow_invalid=*/true);
    if (!enc.ok()) return usage(std::string(codec::error_description(enc.error)));
    if (auto fault = request_fault(codec::Bytes(pdu.data(), enc.size)); !fault.empty())
        return usage(fault);

    const int timeout_ms = static_cast<int>(std::max<std::uint64_t>(o.timeout_ns / 1'000'000, 1));
    if (o.transport.kind() == TransportKind::Serial) return run_serial_io(o, p, pdu, enc.size);
    if (o.target.empty()) return usage("--target is required (or --serial DEVICE)");
    const bool tls_port = o.transport.kind() == TransportKind::Tls;
    Result<net::Endpoint> target = net::parse_endpoint(o.target, tls_port ? 802 : 502);
    if (!target.ok())
        return usage(fmt::format("--target '{}': {}", o.target, target.error().text()));
    p.target = *target;
    p.peer = p.target.to_string();
    if (o.write) {
        load::Operation op;
        op.function = p.request.function;
        auto verdict =
            load::check_write_safety({op}, load::numeric_address(p.target), o.allow_writes);
        if (!verdict.allowed()) return usage(verdict.refusal.text());
    }
    std::shared_ptr<net::TlsContext> tls;
    if (const Error e = client_tls(o.transport, tls); !e.ok()) return fail(name, e);
    ModbusClient client(o.transport.framing_kind());
    if (auto why = client.connect(p.target, timeout_ms, tls); !why.empty())
        return usage(fmt::format("cannot connect to {}: {}", p.target.to_string(), why));

    int exit_code = kExitOk;
    const auto interval = std::chrono::nanoseconds(o.interval_ns);
    auto next = std::chrono::steady_clock::now();
    for (std::uint64_t poll = 1; o.transactions == 0 || poll <= o.transactions; ++poll) {
        codec::Response rsp;
        std::string why = client.transact(static_cast<std::uint8_t>(o.unit),
                                          codec::Bytes(pdu.data(), enc.size), timeout_ms, rsp);
        if (report(o, p, poll, why, rsp) != kExitOk) exit_code = kExitFailed;
        if (why == "the target closed the connection") break;
        if (o.transactions != 0 && poll == o.transactions) break;
        next += interval;
        std::this_thread::sleep_until(next);
    }
    return exit_code;
}

void add_common_options(CLI::App* cmd, IoOptions& o) {
    cmd->add_option("--target", o.target,
                    "HOST[:PORT] of the device (port 502 by default); not with --serial");
    // mbpoll's -a is the unit (slave address): say so where its users look.
    cmd->add_option("--unit,-u", o.unit, "unit id (default 1); mbpoll's -a")
        ->check(CLI::Range(0, 255));
    cmd->add_option("--addr,-a", o.address,
                    "first address (mbpoll users: -a here is the address, the unit is -u): " +
                        std::string(codec::kAddressRuleHelp));
    cmd->add_option("--table", o.table,
                    "coils, discrete_inputs, input_registers or holding_registers (default: the "
                    "reference number's table, else holding_registers)");
    cmd->add_option("--type,-t", o.type,
                    "value type: " + std::string(kValueTypeNames) +
                        " (default u16; bits on coils and discrete inputs)");
    cmd->add_option("--order", o.order,
                    "word/byte order of multi-register values: ABCD (default), CDAB, BADC, DCBA");
    cmd->add_option("-n,--transactions", o.transactions,
                    "how many transactions (default 1; 0: until interrupted)");
    add_deprecated_option(cmd, "--count", "--transactions", o.transactions);
    add_duration_option(cmd, "--interval", o.interval_ns,
                        "time between the starts of two transactions (default 1s)");
    add_duration_option(cmd, "--timeout", o.timeout_ns, "connect and answer timeout (default 1s)");
    cmd->add_flag("--json", o.json, "one JSON object per transaction on stdout");
    cmd->add_flag("--timestamps", o.timestamps,
                  "start each transaction's output with its time, UTC to the millisecond "
                  "(JSON: \"time\")");
    add_transport_options(cmd, o.transport, TransportSide::Client);
}

}  // namespace

void add_read_command(CLI::App& app, Action& action) {
    auto o = std::make_shared<IoOptions>();
    auto* cmd = app.add_subcommand(
        "read", "Read one range of a device once or every --interval, as typed values");
    add_common_options(cmd, *o);
    cmd->add_option(
           "--quantity", o->quantity,
           "how many values of --type (string: characters; default 1, or as many as a range "
           "--addr FIRST-LAST holds)")
        ->check(CLI::Range(1, 65535));
    // -q is --quiet in run and fuzz.
    add_deprecated_option(cmd, "-q", "--quantity", o->quantity)->check(CLI::Range(1, 65535));
    cmd->add_flag("--hex", o->hex,
                  "also show each value's registers in hex, as they came (\"[100]: 3.5 "
                  "0x40600000\"; JSON: \"hex\")");
    cmd->add_flag("--one-based", o->one_based,
                  "number the values from 1 as mbpoll does: [1] is address 0, register 40001 "
                  "(JSON: \"reference\" beside \"address\")");
    cmd->callback([o, cmd, &action] {
        o->quantity_given = cmd->count("--quantity") + cmd->count("-q") != 0;
        action = [o] { return run_io(*o); };
    });
}

void add_write_command(CLI::App& app, Action& action) {
    auto o = std::make_shared<IoOptions>();
    o->write = true;
    auto* cmd = app.add_subcommand(
        "write", "Write values to one range of a device once or every --interval");
    add_common_options(cmd, *o);
    cmd->add_option("values", o->values, "values to write, as --type says")->required();
    cmd->add_option(
        "--fc,-f", o->function,
        fmt::format("force the function: {} for coils, {} for holding registers "
                    "(default: single for one value, multiple otherwise); {}",
                    write_choices(codec::Table::Coils),
                    write_choices(codec::Table::HoldingRegisters), codec::kFunctionCodeForms));
    cmd->add_flag("--allow-writes", o->allow_writes,
                  "allow writing to a target outside loopback (127.0.0.0/8, ::1), or to a "
                  "serial line that is not a pseudo-terminal");
    cmd->callback([o, &action] { action = [o] { return run_io(*o); }; });
}

}  // namespace mbstorm::cli
