// The one rule for the addresses a user writes, in every subcommand, scenario and device file:
//
//   a protocol address: 0-based, what goes on the wire, 0..65535, in decimal ("99") or hex
//     ("0x63");
//   a reference number: the Modicon form, 5 or 6 decimal digits whose first digit names the
//     table (0 coils, 1 discrete inputs, 3 input registers, 4 holding registers) and whose rest
//     is 1-based: "40001" (or "400001") is holding register address 0.
//
// The form alone decides: a 5- or 6-digit decimal starting with 0, 1, 3 or 4 is always a
// reference number, so protocol addresses 10000..19999 and 30000..49999 are written in hex.
// A reference number of another table than the function's is refused, naming the functions
// that address that table.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "codec/function_code.hpp"
#include "codec/values.hpp"

namespace mbstorm::codec {

// "read it with 0x04 read_input_registers", or for a writable table "read it with 0x03
// read_holding_registers, write it with 0x06 ..., 0x10 ..., 0x16 ..., 0x17 ...".
std::string table_functions(Table table);

struct AddressRange {
    std::uint16_t first = 0;
    std::uint16_t last = 0;  // == first for a single address
    bool is_range = false;   // written as FIRST-LAST
    bool reference = false;  // written as reference numbers
};

// Parses one address or a range FIRST-LAST (both ends the same form) for a function that
// addresses `table` (nullopt: the function has no table, so reference numbers are refused).
// Returns "" on success, else one line saying what is wrong and what to write instead.
std::string parse_address_range(std::string_view text, std::optional<Table> table,
                                AddressRange& out);

// A protocol address as text that reads back as the same address under the rule: decimal,
// or hex where the decimal would read as a reference number (40000 -> "0x9C40").
std::string format_protocol_address(std::uint16_t address);

// The rule above in one sentence, for --help texts and error hints.
inline constexpr std::string_view kAddressRuleHelp =
    "a 0-based protocol address 0..65535 (decimal, or 0x hex), a range FIRST-LAST, or "
    "reference numbers like 40001-40100 (5-6 digits starting 0/1/3/4 are always reference "
    "numbers: write protocol addresses 10000..19999 and 30000..49999 in hex)";

}  // namespace mbstorm::codec
