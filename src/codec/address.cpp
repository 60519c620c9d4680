// One parser for every address a user writes (see address.hpp for the rule).
#include "codec/address.hpp"

#include <algorithm>

#include "codec/function_code.hpp"

namespace mbstorm::codec {
namespace {

std::string hex4(std::uint32_t v) {
    constexpr char kDigits[] = "0123456789ABCDEF";
    std::string s = "0x";
    bool started = false;
    for (int shift = 12; shift >= 0; shift -= 4) {
        const unsigned d = (v >> shift) & 0xFu;
        if (d == 0 && !started && shift > 0) continue;
        started = true;
        s += kDigits[d];
    }
    return s;
}

std::string_view table_noun(Table table) noexcept {
    switch (table) {
        case Table::Coils:
            return "a coil";
        case Table::DiscreteInputs:
            return "a discrete input";
        case Table::InputRegisters:
            return "an input register";
        case Table::HoldingRegisters:
            return "a holding register";
    }
    return "an unknown";
}

bool all_digits(std::string_view text) noexcept {
    return !text.empty() &&
           std::all_of(text.begin(), text.end(), [](char c) { return c >= '0' && c <= '9'; });
}

// A 5- or 6-digit decimal starting with a table digit: a reference number by form.
bool reference_form(std::string_view text) noexcept {
    return all_digits(text) && (text.size() == 5 || text.size() == 6) &&
           std::string_view("0134").find(text.front()) != std::string_view::npos;
}

// Decimal or 0x hex, 0..65535.
bool parse_protocol_address(std::string_view text, std::uint16_t& out) noexcept {
    unsigned base = 10;
    if (text.size() > 2 && text[0] == '0' && (text[1] == 'x' || text[1] == 'X')) {
        base = 16;
        text.remove_prefix(2);
    }
    if (text.empty() || text.size() > 6) return false;
    std::uint32_t v = 0;
    for (char c : text) {
        unsigned d;
        if (c >= '0' && c <= '9')
            d = static_cast<unsigned>(c - '0');
        else if (base == 16 && c >= 'a' && c <= 'f')
            d = static_cast<unsigned>(c - 'a' + 10);
        else if (base == 16 && c >= 'A' && c <= 'F')
            d = static_cast<unsigned>(c - 'A' + 10);
        else
            return false;
        v = v * base + d;
    }
    if (v > 0xFFFF) return false;
    out = static_cast<std::uint16_t>(v);
    return true;
}

struct Part {
    std::uint16_t address = 0;
    bool reference = false;
};

std::string parse_part(std::string_view text, std::optional<Table> table, Part& out) {
    const std::string quoted = "'" + std::string(text) + "'";
    if (reference_form(text)) {
        Reference ref;
        const std::string as_address =
            std::stoul(std::string(text)) <= 0xFFFF
                ? "; for protocol address " + std::to_string(std::stoul(std::string(text))) +
                      " write " + hex4(static_cast<std::uint32_t>(std::stoul(std::string(text))))
                : "";
        if (!parse_reference(text, ref)) {
            return quoted + " is not a valid reference number (" + std::string(1, text.front()) +
                   "0001.." + std::string(1, text.front()) + "9999, or " +
                   std::string(1, text.front()) + "00001.." + std::string(1, text.front()) +
                   "65536)" + as_address;
        }
        if (!table) {
            return quoted + " is " + std::string(table_noun(ref.table)) +
                   " reference number, but this function addresses no table";
        }
        if (ref.table != *table) {
            return quoted + " is " + std::string(table_noun(ref.table)) +
                   " reference: " + table_functions(ref.table) + as_address;
        }
        out = {ref.offset, true};
        return {};
    }
    if (!parse_protocol_address(text, out.address)) {
        return quoted + " is not an address: give " + std::string(kAddressRuleHelp);
    }
    out.reference = false;
    return {};
}

}  // namespace

std::string table_functions(Table table) {
    switch (table) {
        case Table::Coils:
            return "read it with " + function_label(0x01) + ", write it with " +
                   function_label(0x05) + " or " + function_label(0x0F);
        case Table::DiscreteInputs:
            return "read it with " + function_label(0x02);
        case Table::InputRegisters:
            return "read it with " + function_label(0x04);
        case Table::HoldingRegisters:
            return "read it with " + function_label(0x03) + " or " + function_label(0x17) +
                   ", write it with " + function_label(0x06) + ", " + function_label(0x10) +
                   " or " + function_label(0x16);
    }
    return {};
}

std::string format_protocol_address(std::uint16_t address) {
    const std::string decimal = std::to_string(address);
    return reference_form(decimal) ? hex4(address) : decimal;
}

std::string parse_address_range(std::string_view text, std::optional<Table> table,
                                AddressRange& out) {
    const auto dash = text.find('-');
    Part first, last;
    if (auto error = parse_part(text.substr(0, dash), table, first); !error.empty()) return error;
    if (dash == std::string_view::npos) {
        out = {first.address, first.address, false, first.reference};
        return {};
    }
    if (auto error = parse_part(text.substr(dash + 1), table, last); !error.empty()) return error;
    const std::string quoted = "'" + std::string(text) + "'";
    if (first.reference != last.reference) {
        return quoted +
               " mixes a reference number and a protocol address: write both ends the same way";
    }
    if (last.address < first.address) {
        return quoted + " ends before it starts (FIRST must be <= LAST)";
    }
    out = {first.address, last.address, true, first.reference};
    return {};
}

}  // namespace mbstorm::codec
