// `mbstorm encode`: builds a request frame from fields and prints it as hex.
#include <fmt/format.h>

#include <array>
#include <cstdio>
#include <string>
#include <vector>

#include "cli/commands.hpp"
#include "codec/ascii.hpp"
#include "codec/function_code.hpp"
#include "codec/limits.hpp"
#include "codec/mbap.hpp"
#include "codec/pdu.hpp"
#include "codec/rtu.hpp"
#include "codec/values.hpp"

namespace mbstorm::cli {
namespace {

struct EncodeOptions {
    std::string function;   // number or name
    std::string reference;  // e.g. 40001: sets function table and address
    int address = 0;
    int count = 1;
    int value = 0;
    std::vector<int> values;
    int and_mask = 0xFFFF, or_mask = 0;
    int write_address = 0;
    int sub_function = 0;
    int file = 1, record = 0;
    int device_id_code = 1, object_id = 0;
    int unit = 1;
    int transaction_id = 1;
    int exception = 0;
    bool rtu = false, ascii = false, pdu = false;
};

bool parse_function(const std::string& text, std::uint8_t& fc) {
    if (codec::function_from_name(text, fc)) return true;
    try {
        std::size_t used = 0;
        int v = std::stoi(text, &used, 0);
        if (used != text.size() || v < 1 || v > 127) return false;
        fc = static_cast<std::uint8_t>(v);
        return true;
    } catch (...) {
        return false;
    }
}

int fail(const std::string& msg) {
    fmt::print(stderr, "mbstorm encode: {}\n", msg);
    return kExitUsage;
}

int run_encode(EncodeOptions o) {
    std::uint8_t fc = 0;
    if (!o.reference.empty()) {
        codec::Reference ref;
        if (!codec::parse_reference(o.reference, ref))
            return fail(
                fmt::format("bad reference number '{}' (e.g. 00001, 10001, 30001, 40001, 400001)",
                            o.reference));
        o.address = ref.offset;
        if (o.function.empty()) {
            static constexpr std::uint8_t read_fc[] = {1, 2, 4, 3};
            fc = read_fc[static_cast<int>(ref.table)];
        }
    }
    if (!o.function.empty() && !parse_function(o.function, fc))
        return fail(fmt::format(
            "unknown function '{}' (a number 1..127 or a name like read_holding_registers)",
            o.function));
    if (fc == 0) return fail("--fc (or --ref) is required");

    std::array<std::uint8_t, codec::limits::kMaxPdu> payload{};
    std::array<std::uint8_t, codec::limits::kMaxPdu> pdu{};
    codec::EncodeResult enc;
    if (o.exception) {
        enc = codec::encode_exception(fc, static_cast<codec::ExceptionCode>(o.exception), pdu);
    } else {
        codec::Request r;
        r.function = fc;
        r.address = static_cast<std::uint16_t>(o.address);
        r.quantity = static_cast<std::uint16_t>(o.count);
        r.value = static_cast<std::uint16_t>(o.value);
        r.and_mask = static_cast<std::uint16_t>(o.and_mask);
        r.or_mask = static_cast<std::uint16_t>(o.or_mask);
        r.sub_function = static_cast<std::uint16_t>(o.sub_function);
        r.mei_type = codec::kMeiReadDeviceId;
        r.device_id_code = static_cast<std::uint8_t>(o.device_id_code);
        r.object_id = static_cast<std::uint8_t>(o.object_id);
        std::size_t n = 0;
        using FC = codec::FunctionCode;
        switch (static_cast<FC>(fc)) {
            case FC::WriteSingleCoil:
                r.value = o.value ? codec::limits::kCoilOn : codec::limits::kCoilOff;
                break;
            case FC::WriteMultipleCoils: {
                std::vector<std::uint8_t> bits(o.values.begin(), o.values.end());
                auto packed = codec::pack_bit_bytes(bits, payload);
                if (!packed.ok()) return fail("too many coil values");
                r.quantity = static_cast<std::uint16_t>(bits.size());
                n = packed.size;
                break;
            }
            case FC::WriteMultipleRegisters:
            case FC::ReadWriteMultipleRegisters:
            case FC::Diagnostics:
                if (o.values.size() * 2 > payload.size()) return fail("too many values");
                for (int v : o.values) {
                    codec::store_be16(payload.data() + n, static_cast<std::uint16_t>(v));
                    n += 2;
                }
                if (fc == codec::to_byte(FC::WriteMultipleRegisters))
                    r.quantity = static_cast<std::uint16_t>(o.values.size());
                if (fc == codec::to_byte(FC::ReadWriteMultipleRegisters)) {
                    r.write_address = static_cast<std::uint16_t>(o.write_address);
                    r.write_quantity = static_cast<std::uint16_t>(o.values.size());
                }
                break;
            case FC::ReadFileRecord:
            case FC::WriteFileRecord: {
                bool write = fc == codec::to_byte(FC::WriteFileRecord);
                std::uint16_t length =
                    static_cast<std::uint16_t>(write ? o.values.size() : o.count);
                payload[n++] = codec::limits::kFileReferenceType;
                codec::store_be16(payload.data() + n, static_cast<std::uint16_t>(o.file));
                codec::store_be16(payload.data() + n + 2, static_cast<std::uint16_t>(o.record));
                codec::store_be16(payload.data() + n + 4, length);
                n += 6;
                if (write) {
                    if (n + o.values.size() * 2 > payload.size()) return fail("too many values");
                    for (int v : o.values) {
                        codec::store_be16(payload.data() + n, static_cast<std::uint16_t>(v));
                        n += 2;
                    }
                }
                break;
            }
            default:
                break;
        }
        r.payload = codec::Bytes(payload.data(), n);
        enc = codec::encode_request(r, pdu);
        if (enc.error == codec::CodecError::InvalidArgument)
            return fail(
                fmt::format("these fields do not form a valid {} request (check the quantity "
                            "limits of the Modbus specification)",
                            codec::function_name(fc)));
    }
    if (!enc.ok()) return fail(std::string(codec::error_description(enc.error)));

    codec::Bytes pdu_bytes(pdu.data(), enc.size);
    std::array<std::uint8_t, codec::limits::kMaxAsciiAdu> frame{};
    codec::EncodeResult framed;
    if (o.pdu) {
        fmt::print("{}\n", codec::format_hex(pdu_bytes));
        return kExitOk;
    }
    if (o.rtu) {
        framed = codec::encode_rtu_frame(static_cast<std::uint8_t>(o.unit), pdu_bytes, frame);
    } else if (o.ascii) {
        framed = codec::encode_ascii_frame(static_cast<std::uint8_t>(o.unit), pdu_bytes, frame);
        if (framed.ok()) {
            // Print the text without the CR LF terminator.
            fmt::print("{}\n", std::string(frame.begin(), frame.begin() + framed.size - 2));
            return kExitOk;
        }
    } else {
        framed = codec::encode_tcp_frame(static_cast<std::uint16_t>(o.transaction_id),
                                         static_cast<std::uint8_t>(o.unit), pdu_bytes, frame);
    }
    if (!framed.ok()) return fail(std::string(codec::error_description(framed.error)));
    fmt::print("{}\n", codec::format_hex(codec::Bytes(frame.data(), framed.size)));
    return kExitOk;
}

}  // namespace

void add_encode_command(CLI::App& app, Action& action) {
    auto o = std::make_shared<EncodeOptions>();
    auto* cmd =
        app.add_subcommand("encode", "Build a request frame from fields and print it as hex");
    cmd->add_option("--fc,-f", o->function,
                    "function code (number) or name, e.g. 3 or read_holding_registers");
    cmd->add_option("--ref", o->reference,
                    "reference number (40001 = holding register 0); picks the read function");
    cmd->add_option("--addr,-a", o->address, "starting address (0-based)")
        ->check(CLI::Range(0, 65535));
    cmd->add_option("--count,-n", o->count, "quantity (bits or registers)")
        ->check(CLI::Range(0, 65535));
    cmd->add_option("--value", o->value, "value for FC05 (0/1) and FC06")
        ->check(CLI::Range(0, 65535));
    cmd->add_option("--values", o->values, "values for FC0F/10/15/17 and FC08 data")
        ->delimiter(',')
        ->check(CLI::Range(0, 65535));
    cmd->add_option("--and", o->and_mask, "AND mask for FC16")->check(CLI::Range(0, 65535));
    cmd->add_option("--or", o->or_mask, "OR mask for FC16")->check(CLI::Range(0, 65535));
    cmd->add_option("--write-addr", o->write_address, "write address for FC17")
        ->check(CLI::Range(0, 65535));
    cmd->add_option("--sub", o->sub_function, "FC08 sub-function")->check(CLI::Range(0, 65535));
    cmd->add_option("--file", o->file, "file number for FC14/15")->check(CLI::Range(0, 65535));
    cmd->add_option("--record", o->record, "record number for FC14/15")->check(CLI::Range(0, 9999));
    cmd->add_option("--device-id-code", o->device_id_code, "FC2B/0E read device id code")
        ->check(CLI::Range(1, 4));
    cmd->add_option("--object", o->object_id, "FC2B/0E object id")->check(CLI::Range(0, 255));
    cmd->add_option("--unit,-u", o->unit, "unit id (TCP) or slave address (RTU/ASCII)")
        ->check(CLI::Range(0, 255));
    cmd->add_option("--tid", o->transaction_id, "MBAP transaction id")->check(CLI::Range(0, 65535));
    cmd->add_option("--exception", o->exception,
                    "build an exception response with this code instead")
        ->check(CLI::Range(1, 255));
    auto* rtu = cmd->add_flag("--rtu", o->rtu, "RTU framing (address + PDU + CRC)");
    auto* ascii = cmd->add_flag("--ascii", o->ascii, "ASCII framing");
    auto* pdu = cmd->add_flag("--pdu", o->pdu, "bare PDU");
    rtu->excludes(ascii, pdu);
    ascii->excludes(pdu);
    cmd->callback([o, &action] { action = [o] { return run_encode(*o); }; });
}

}  // namespace mbstorm::cli
