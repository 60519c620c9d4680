// `mbstorm encode`: builds a request frame from fields and prints it as hex.
#include <fmt/format.h>

#include <array>
#include <cstdio>
#include <string>
#include <vector>

#include "cli/commands.hpp"
#include "cli/deprecated_option.hpp"
#include "cli/frame_describe.hpp"
#include "codec/address.hpp"
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
    std::string address = "0";
    int quantity = 1;
    int value = 0;
    std::vector<int> values;
    int and_mask = 0xFFFF, or_mask = 0;
    std::string write_address = "0";
    int sub_function = 0;
    int file = 1, record = 0;
    int device_id_code = 1, object_id = 0;
    int unit = 1;
    int transaction_id = 1;
    int exception = 0;
    bool rtu = false, ascii = false, pdu = false;
};

// "valid: 0x01 0x02 ...": the public function codes this tool encodes, for refusals.
std::string valid_functions() {
    std::string text = "valid:";
    for (const codec::FunctionInfo& f : codec::public_functions())
        text += fmt::format(" 0x{:02X}", codec::to_byte(f.code));
    return text + " (or decimal, or a name like read_holding_registers)";
}

// Counts given as --values must fit the function's quantity range before they are packed.
std::string values_fault(std::uint8_t fc, std::size_t given) {
    const codec::FunctionInfo* f = codec::function_info(fc);
    if (f == nullptr) return {};
    std::uint16_t max = 0;
    switch (f->request) {
        case codec::RequestShape::MultipleCoils:
            max = codec::limits::kMaxWriteCoils;
            break;
        case codec::RequestShape::MultipleRegisters:
            max = codec::limits::kMaxWriteRegisters;
            break;
        case codec::RequestShape::ReadWriteRegisters:
            max = codec::limits::kMaxRwWriteRegisters;
            break;
        case codec::RequestShape::FileRecords:
            if (!f->writes) return {};
            // One sub-request: 7 header bytes + 2 per register within the byte count.
            max = (codec::limits::kMaxFileWriteBytes - 7) / 2;
            break;
        case codec::RequestShape::FunctionOnly:
        case codec::RequestShape::AddressQuantity:
        case codec::RequestShape::SingleCoil:
        case codec::RequestShape::SingleRegister:
        case codec::RequestShape::SubFunction:
        case codec::RequestShape::MaskWrite:
        case codec::RequestShape::FifoPointer:
        case codec::RequestShape::MeiTransport:
            return {};  // no --values count to check
    }
    if (given >= 1 && given <= max) return {};
    return fmt::format("--values holds {} value(s): valid 1..{} for {}", given, max,
                       codec::function_label(fc));
}

// FC14/15 build one sub-request from --file, --record and the record length.
std::string file_fault(std::uint8_t fc, int file, int record, std::size_t length) {
    if (!codec::request_is(fc, codec::RequestShape::FileRecords)) return {};
    const bool reads = !codec::is_write_function(fc);
    // FC14: each sub-response takes 2 bytes + 2 per register within the response's byte count.
    const std::size_t max_read = (codec::limits::kMaxFileResponseBytes - 2) / 2;
    if (reads && (length < 1 || length > max_read))
        return fmt::format("--quantity {} (record length): valid 1..{} for {}", length, max_read,
                           codec::function_label(fc));
    if (file < codec::limits::kMinFileNumber)
        return fmt::format("--file {}: valid 1..65535 for {}", file, codec::function_label(fc));
    if (record + length > codec::limits::kMaxFileRecordNumber + 1u)
        return fmt::format("--record {} + record length {} runs past record {}", record, length,
                           codec::limits::kMaxFileRecordNumber);
    return {};
}

// Which function to encode: --fc, or the read function of --ref's (or --addr's) table.
// Fills `o.reference` when --addr holds a reference number. "" on success, else the refusal.
std::string resolve_function(EncodeOptions& o, std::uint8_t& fc) {
    fc = 0;
    if (codec::Reference ref;
        o.function.empty() && o.reference.empty() && codec::parse_reference(o.address, ref))
        o.reference = o.address;
    if (!o.reference.empty()) {
        codec::Reference ref;
        if (!codec::parse_reference(o.reference, ref))
            return fmt::format(
                "bad reference number '{}' (e.g. 00001, 10001, 30001, 40001, 400001)", o.reference);
        if (o.function.empty()) {
            fc = codec::function_for(ref.table, codec::RequestShape::AddressQuantity);
        }
    }
    if (!o.function.empty()) {
        if (auto error = codec::parse_function_code(o.function, fc); !error.empty())
            return "--fc: " + error;
    }
    if (fc == 0) return "--fc (or --ref) is required";
    if (!o.exception && !codec::is_supported_function(fc))
        return fmt::format("function code {} ({}): not a public Modbus function; {}", o.function,
                           codec::function_label(fc), valid_functions());
    return {};
}

// --ref or --addr, and for FC17 --write-addr, under the one address rule: one address each,
// suiting the function's table. "" on success, else the refusal.
std::string resolve_addresses(const EncodeOptions& o, std::uint8_t fc, std::uint16_t& address,
                              std::uint16_t& write_address) {
    const std::string& text = o.reference.empty() ? o.address : o.reference;
    codec::AddressRange range;
    auto error = codec::parse_address_range(text, codec::function_table(fc), range);
    if (error.empty() && range.is_range) error = "'" + text + "' is a range: give one";
    if (!error.empty()) return (o.reference.empty() ? "--addr " : "--ref ") + error;
    address = range.first;
    write_address = 0;
    if (codec::request_is(fc, codec::RequestShape::ReadWriteRegisters)) {
        error = codec::parse_address_range(o.write_address, codec::Table::HoldingRegisters, range);
        if (error.empty() && range.is_range) error = "'" + o.write_address + "' is a range";
        if (!error.empty()) return "--write-addr " + error;
        write_address = range.first;
    }
    return {};
}

// Options the decoder cannot judge, because they are packed before it sees them.
std::string option_fault(const EncodeOptions& o, std::uint8_t fc) {
    if (auto fault = values_fault(fc, o.values.size()); !fault.empty()) return fault;
    const std::size_t file_length =
        codec::request_is(fc, codec::RequestShape::FileRecords) && codec::is_write_function(fc)
            ? o.values.size()
            : static_cast<std::size_t>(o.quantity);
    if (auto fault = file_fault(fc, o.file, o.record, file_length); !fault.empty()) return fault;
    if (codec::request_is(fc, codec::RequestShape::SingleCoil) && o.value != 0 && o.value != 1 &&
        o.value != codec::limits::kCoilOn)
        return fmt::format("--value {} for {}: valid 0 (OFF) or 1 (ON)", o.value,
                           codec::function_label(fc));
    return {};
}

// The request the options describe; its payload is packed into `payload`. "" on success.
std::string build_request(const EncodeOptions& o, std::uint8_t fc, std::uint16_t address,
                          std::uint16_t write_address,
                          std::array<std::uint8_t, codec::limits::kMaxPdu>& payload,
                          codec::Request& r) {
    r = codec::Request{};
    r.function = fc;
    r.address = address;
    r.quantity = static_cast<std::uint16_t>(o.quantity);
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
            if (!packed.ok()) return "too many coil values";
            r.quantity = static_cast<std::uint16_t>(bits.size());
            n = packed.size;
            break;
        }
        case FC::WriteMultipleRegisters:
        case FC::ReadWriteMultipleRegisters:
        case FC::Diagnostics:
            if (o.values.size() * 2 > payload.size()) return "too many values";
            for (int v : o.values) {
                codec::store_be16(payload.data() + n, static_cast<std::uint16_t>(v));
                n += 2;
            }
            if (fc == codec::to_byte(FC::WriteMultipleRegisters))
                r.quantity = static_cast<std::uint16_t>(o.values.size());
            if (fc == codec::to_byte(FC::ReadWriteMultipleRegisters)) {
                r.write_address = write_address;
                r.write_quantity = static_cast<std::uint16_t>(o.values.size());
            }
            break;
        case FC::ReadFileRecord:
        case FC::WriteFileRecord: {
            const bool write = fc == codec::to_byte(FC::WriteFileRecord);
            std::vector<std::uint8_t> data;
            for (int v : o.values) {
                data.push_back(static_cast<std::uint8_t>(v >> 8));
                data.push_back(static_cast<std::uint8_t>(v & 0xFF));
            }
            codec::FileSubRequest sub;
            sub.reference_type = codec::limits::kFileReferenceType;
            sub.file_number = static_cast<std::uint16_t>(o.file);
            sub.record_number = static_cast<std::uint16_t>(o.record);
            sub.record_length = static_cast<std::uint16_t>(write ? o.values.size() : o.quantity);
            if (write) sub.record_data = data;
            const codec::EncodeResult written = codec::encode_file_sub_request(sub, payload);
            if (!written.ok()) return "too many values";
            n = written.size;
            break;
        }
        case FC::ReadCoils:
        case FC::ReadDiscreteInputs:
        case FC::ReadHoldingRegisters:
        case FC::ReadInputRegisters:
        case FC::WriteSingleRegister:
        case FC::ReadExceptionStatus:
        case FC::GetCommEventCounter:
        case FC::GetCommEventLog:
        case FC::ReportServerId:
        case FC::MaskWriteRegister:
        case FC::ReadFifoQueue:
        case FC::EncapsulatedInterface:
            break;  // the fields set above are the whole request
    }
    r.payload = codec::Bytes(payload.data(), n);
    return {};
}

// Prints the PDU as hex (--pdu), or framed: RTU, ASCII text, or MBAP (the default).
int print_framed(const EncodeOptions& o, codec::Bytes pdu) {
    if (o.pdu) {
        fmt::print("{}\n", codec::format_hex(pdu));
        return kExitOk;
    }
    std::array<std::uint8_t, codec::limits::kMaxAsciiAdu> frame{};
    codec::EncodeResult framed;
    if (o.rtu) {
        framed = codec::encode_rtu_frame(static_cast<std::uint8_t>(o.unit), pdu, frame);
    } else if (o.ascii) {
        framed = codec::encode_ascii_frame(static_cast<std::uint8_t>(o.unit), pdu, frame);
        if (framed.ok()) {
            // Print the text without the CR LF terminator.
            fmt::print("{}\n", std::string(frame.begin(), frame.begin() + framed.size - 2));
            return kExitOk;
        }
    } else {
        framed = codec::encode_tcp_frame(static_cast<std::uint16_t>(o.transaction_id),
                                         static_cast<std::uint8_t>(o.unit), pdu, frame);
    }
    if (!framed.ok())
        return usage_error("encode", std::string(codec::error_description(framed.error)));
    fmt::print("{}\n", codec::format_hex(codec::Bytes(frame.data(), framed.size)));
    return kExitOk;
}

int run_encode(EncodeOptions o) {
    std::uint8_t fc = 0;
    if (auto error = resolve_function(o, fc); !error.empty()) return usage_error("encode", error);
    std::uint16_t address = 0, write_address = 0;
    if (auto error = resolve_addresses(o, fc, address, write_address); !error.empty())
        return usage_error("encode", error);
    if (!o.exception) {
        if (auto fault = option_fault(o, fc); !fault.empty()) return usage_error("encode", fault);
    }

    std::array<std::uint8_t, codec::limits::kMaxPdu> payload{};
    std::array<std::uint8_t, codec::limits::kMaxPdu> pdu{};
    codec::EncodeResult enc;
    if (o.exception) {
        enc = codec::encode_exception(fc, static_cast<codec::ExceptionCode>(o.exception), pdu);
    } else {
        codec::Request r;
        if (auto error = build_request(o, fc, address, write_address, payload, r); !error.empty())
            return usage_error("encode", error);
        // Built without checks, then judged by the decoder, so the refusal names the field.
        enc = codec::encode_request(r, pdu, /*allow_invalid=*/true);
        if (enc.ok()) {
            auto fault = request_fault(codec::Bytes(pdu.data(), enc.size));
            if (!fault.empty()) return usage_error("encode", fault);
        }
    }
    if (!enc.ok()) return usage_error("encode", std::string(codec::error_description(enc.error)));
    return print_framed(o, codec::Bytes(pdu.data(), enc.size));
}

}  // namespace

void add_encode_command(CLI::App& app, Action& action) {
    auto o = std::make_shared<EncodeOptions>();
    auto* cmd =
        app.add_subcommand("encode", "Build a request frame from fields and print it as hex");
    cmd->add_option("--fc,-f", o->function,
                    "function code: " + std::string(codec::kFunctionCodeForms));
    cmd->add_option("--ref", o->reference,
                    "reference number (40001 = holding register 0); picks the read function");
    cmd->add_option("--addr,-a", o->address,
                    "starting address: " + std::string(codec::kAddressRuleHelp));
    cmd->add_option("--quantity", o->quantity, "registers or bits (FC14: the record length)")
        ->check(CLI::Range(0, 65535));
    for (const char* old_name : {"--count", "-n"})
        add_deprecated_option(cmd, old_name, "--quantity", o->quantity)
            ->check(CLI::Range(0, 65535));
    cmd->add_option("--value", o->value, "value for FC05 (0/1) and FC06")
        ->check(CLI::Range(0, 65535));
    cmd->add_option("--values", o->values, "values for FC0F/10/15/17 and FC08 data")
        ->delimiter(',')
        ->check(CLI::Range(0, 65535));
    cmd->add_option("--and", o->and_mask, "AND mask for FC16")->check(CLI::Range(0, 65535));
    cmd->add_option("--or", o->or_mask, "OR mask for FC16")->check(CLI::Range(0, 65535));
    cmd->add_option("--write-addr", o->write_address,
                    "write address for FC17 (same rule as --addr)");
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
