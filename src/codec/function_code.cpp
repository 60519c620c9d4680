// Names and classification of the public function codes.
#include "codec/function_code.hpp"

#include <array>

namespace mbstorm::codec {
namespace {

struct FunctionInfo {
    std::uint8_t code;
    std::string_view name;
    bool writes;
};

// Kept in code order; the table is small enough that a linear scan beats anything fancier.
constexpr std::array<FunctionInfo, 19> kFunctions{{
    {0x01, "read_coils", false},
    {0x02, "read_discrete_inputs", false},
    {0x03, "read_holding_registers", false},
    {0x04, "read_input_registers", false},
    {0x05, "write_single_coil", true},
    {0x06, "write_single_register", true},
    {0x07, "read_exception_status", false},
    {0x08, "diagnostics", true},
    {0x0B, "get_comm_event_counter", false},
    {0x0C, "get_comm_event_log", false},
    {0x0F, "write_multiple_coils", true},
    {0x10, "write_multiple_registers", true},
    {0x11, "report_server_id", false},
    {0x14, "read_file_record", false},
    {0x15, "write_file_record", true},
    {0x16, "mask_write_register", true},
    {0x17, "read_write_multiple_registers", true},
    {0x18, "read_fifo_queue", false},
    {0x2B, "encapsulated_interface", false},
}};

const FunctionInfo* find(std::uint8_t fc) noexcept {
    for (const auto& f : kFunctions) {
        if (f.code == fc) return &f;
    }
    return nullptr;
}

}  // namespace

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
            fc = f.code;
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
