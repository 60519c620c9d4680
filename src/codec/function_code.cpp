// Names and classification of the public function codes.
#include "codec/function_code.hpp"

#include <array>

namespace mbstorm::codec {
namespace {

using enum FunctionCode;
using enum RequestShape;
using Kind = FunctionKind;
using Rsp = ResponseShape;
namespace lim = limits;

constexpr lim::QuantityRange kNoQuantity{};
constexpr lim::QuantityRange kOne{1, 1};

// Kept in code order (public_function_codes() promises it).
constexpr std::array<FunctionInfo, 19> kFunctions{{
    {ReadCoils,
     "read_coils",
     Kind::Read,
     false,
     Table::Coils,
     {1, lim::kMaxReadBits},
     AddressQuantity,
     Rsp::Bits},
    {ReadDiscreteInputs,
     "read_discrete_inputs",
     Kind::Read,
     false,
     Table::DiscreteInputs,
     {1, lim::kMaxReadBits},
     AddressQuantity,
     Rsp::Bits},
    {ReadHoldingRegisters,
     "read_holding_registers",
     Kind::Read,
     false,
     Table::HoldingRegisters,
     {1, lim::kMaxReadRegisters},
     AddressQuantity,
     Rsp::Registers},
    {ReadInputRegisters,
     "read_input_registers",
     Kind::Read,
     false,
     Table::InputRegisters,
     {1, lim::kMaxReadRegisters},
     AddressQuantity,
     Rsp::Registers},
    {WriteSingleCoil, "write_single_coil", Kind::Write, true, Table::Coils, kOne, SingleCoil,
     Rsp::EchoValue},
    {WriteSingleRegister, "write_single_register", Kind::Write, true, Table::HoldingRegisters, kOne,
     SingleRegister, Rsp::EchoValue},
    {ReadExceptionStatus, "read_exception_status", Kind::Diagnostic, false, std::nullopt,
     kNoQuantity, FunctionOnly, Rsp::ExceptionStatus},
    {Diagnostics, "diagnostics", Kind::Diagnostic, true, std::nullopt, kNoQuantity, SubFunction,
     Rsp::EchoSubFunction},
    {GetCommEventCounter, "get_comm_event_counter", Kind::Diagnostic, false, std::nullopt,
     kNoQuantity, FunctionOnly, Rsp::EventCounter},
    {GetCommEventLog, "get_comm_event_log", Kind::Diagnostic, false, std::nullopt, kNoQuantity,
     FunctionOnly, Rsp::EventLog},
    {WriteMultipleCoils,
     "write_multiple_coils",
     Kind::Write,
     true,
     Table::Coils,
     {1, lim::kMaxWriteCoils},
     MultipleCoils,
     Rsp::EchoQuantity},
    {WriteMultipleRegisters,
     "write_multiple_registers",
     Kind::Write,
     true,
     Table::HoldingRegisters,
     {1, lim::kMaxWriteRegisters},
     MultipleRegisters,
     Rsp::EchoQuantity},
    {ReportServerId, "report_server_id", Kind::Diagnostic, false, std::nullopt, kNoQuantity,
     FunctionOnly, Rsp::ServerId},
    {ReadFileRecord, "read_file_record", Kind::Read, false, std::nullopt, kNoQuantity, FileRecords,
     Rsp::FileRecords},
    {WriteFileRecord, "write_file_record", Kind::Write, true, std::nullopt, kNoQuantity,
     FileRecords, Rsp::FileRecords},
    {MaskWriteRegister, "mask_write_register", Kind::Write, true, Table::HoldingRegisters, kOne,
     MaskWrite, Rsp::EchoMask},
    {ReadWriteMultipleRegisters,
     "read_write_multiple_registers",
     Kind::Write,
     true,
     Table::HoldingRegisters,
     {1, lim::kMaxRwReadRegisters},
     ReadWriteRegisters,
     Rsp::Registers},
    {ReadFifoQueue, "read_fifo_queue", Kind::Read, false, Table::HoldingRegisters, kNoQuantity,
     FifoPointer, Rsp::FifoValues},
    {EncapsulatedInterface, "encapsulated_interface", Kind::Read, false, std::nullopt, kNoQuantity,
     MeiTransport, Rsp::MeiObjects},
}};

constexpr std::array<std::uint8_t, kFunctions.size()> kCodes = [] {
    std::array<std::uint8_t, kFunctions.size()> codes{};
    for (std::size_t i = 0; i < kFunctions.size(); ++i) codes[i] = to_byte(kFunctions[i].code);
    return codes;
}();

// Row of each code in kFunctions, kNone for unknown codes: the load engine asks per request.
constexpr std::uint8_t kNone = 0xFF;
constexpr std::array<std::uint8_t, 256> kRowOf = [] {
    std::array<std::uint8_t, 256> rows{};
    rows.fill(kNone);
    for (std::size_t i = 0; i < kFunctions.size(); ++i) {
        rows[to_byte(kFunctions[i].code)] = static_cast<std::uint8_t>(i);
    }
    return rows;
}();

const FunctionInfo* find(std::uint8_t fc) noexcept {
    const std::uint8_t row = kRowOf[fc];
    return row == kNone ? nullptr : &kFunctions[row];
}

}  // namespace

std::span<const FunctionInfo> public_functions() noexcept {
    return kFunctions;
}

std::span<const std::uint8_t> public_function_codes() noexcept {
    return kCodes;
}

const FunctionInfo* function_info(std::uint8_t fc) noexcept {
    return find(fc);
}

limits::QuantityRange quantity_range(std::uint8_t fc) noexcept {
    const FunctionInfo* f = find(fc);
    return f != nullptr ? f->quantity : limits::QuantityRange{};
}

std::optional<Table> function_table(std::uint8_t fc) noexcept {
    const FunctionInfo* f = find(fc);
    return f != nullptr ? f->table : std::nullopt;
}

std::uint8_t function_for(Table table, RequestShape shape) noexcept {
    for (const FunctionInfo& f : public_functions())
        if (f.table == table && f.request == shape) return to_byte(f.code);
    return 0;
}

AddressFields address_fields(RequestShape shape) noexcept {
    switch (shape) {
        case RequestShape::AddressQuantity:
        case RequestShape::SingleCoil:
        case RequestShape::SingleRegister:
        case RequestShape::MultipleCoils:
        case RequestShape::MultipleRegisters:
        case RequestShape::MaskWrite:
        case RequestShape::FifoPointer:
            return {1, 0};
        case RequestShape::ReadWriteRegisters:
            return {1, 5};
        case RequestShape::FunctionOnly:
        case RequestShape::SubFunction:
        case RequestShape::FileRecords:
        case RequestShape::MeiTransport:
            return {};
    }
    return {};
}

RequestFields request_fields(std::uint8_t fc) noexcept {
    const FunctionInfo* f = find(fc);
    if (f == nullptr) return {};
    switch (f->request) {
        case RequestShape::AddressQuantity:
            return {3, 0, 0, 0, 0, f->quantity, {}, false};
        case RequestShape::MultipleCoils:
            return {3, 3, 5, 6, 0, f->quantity, f->quantity, true};
        case RequestShape::MultipleRegisters:
            return {3, 3, 5, 6, 0, f->quantity, f->quantity, false};
        case RequestShape::ReadWriteRegisters:
            return {3, 7, 9, 10, 0, f->quantity, {1, limits::kMaxRwWriteRegisters}, false};
        case RequestShape::SingleCoil: {
            RequestFields value_only;
            value_only.coil_value = 3;
            return value_only;
        }
        case RequestShape::FunctionOnly:
        case RequestShape::SingleRegister:
        case RequestShape::SubFunction:
        case RequestShape::FileRecords:
        case RequestShape::MaskWrite:
        case RequestShape::FifoPointer:
        case RequestShape::MeiTransport:
            return {};
    }
    return {};
}

bool request_is(std::uint8_t fc, RequestShape shape) noexcept {
    const FunctionInfo* f = find(fc);
    return f != nullptr && f->request == shape;
}

bool response_is(std::uint8_t fc, ResponseShape shape) noexcept {
    const FunctionInfo* f = find(fc);
    return f != nullptr && f->response == shape;
}

bool is_supported_function(std::uint8_t fc) noexcept {
    return find(fc) != nullptr;
}

bool is_write_function(std::uint8_t fc) noexcept {
    const FunctionInfo* f = find(fc);
    return f != nullptr && f->writes;
}

std::string_view function_name(std::uint8_t fc) noexcept {
    const FunctionInfo* f = find(fc);
    return f != nullptr ? f->name : std::string_view{};
}

bool function_from_name(std::string_view name, std::uint8_t& fc) noexcept {
    for (const auto& f : kFunctions) {
        if (f.name == name) {
            fc = to_byte(f.code);
            return true;
        }
    }
    return false;
}

std::string function_label(std::uint8_t fc) {
    constexpr char kDigits[] = "0123456789ABCDEF";
    std::string s = {'0', 'x', kDigits[fc >> 4], kDigits[fc & 0xFu]};
    const std::string_view name = function_name(fc);
    if (!name.empty()) {
        s += ' ';
        s += name;
    }
    return s;
}

std::string parse_function_code(std::string_view text, std::uint8_t& fc) {
    if (function_from_name(text, fc)) return {};
    std::string_view digits = text;
    unsigned base = 10;
    if (digits.size() > 2 && digits[0] == '0' && (digits[1] == 'x' || digits[1] == 'X')) {
        base = 16;
        digits.remove_prefix(2);
    }
    // At most 3 significant digits keep the value far from overflow; leading zeros are fine.
    while (digits.size() > 1 && digits.front() == '0') digits.remove_prefix(1);
    bool valid = !digits.empty() && digits.size() <= 3;
    unsigned value = 0;
    for (char c : digits) {
        unsigned d = 16;
        if (c >= '0' && c <= '9') d = static_cast<unsigned>(c - '0');
        if (base == 16 && c >= 'a' && c <= 'f') d = static_cast<unsigned>(c - 'a' + 10);
        if (base == 16 && c >= 'A' && c <= 'F') d = static_cast<unsigned>(c - 'A' + 10);
        if (d >= base) {
            valid = false;
            break;
        }
        value = value * base + d;
    }
    if (valid && value >= 1 && value <= 0x7F) {
        fc = static_cast<std::uint8_t>(value);
        return {};
    }
    std::string why = valid ? " is out of range 1..127 (0x01..0x7F)" : " is not a function code";
    return "function '" + std::string(text) + "'" + why + "; write " +
           std::string(kFunctionCodeForms);
}

}  // namespace mbstorm::codec
