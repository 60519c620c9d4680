// Value helpers: coil bit packing, multi-register numbers in the four common word/byte
// orders, Modicon reference numbers ("40001") and hex text for the CLI.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "codec/bytes.hpp"
#include "codec/error.hpp"
#include "codec/pdu.hpp"
#include "codec/table.hpp"

namespace mbstorm::codec {

// ---- Bits (FC01/02 responses, FC0F requests): LSB of the first byte is the first bit, the
// unused high bits of the last byte are zero.

constexpr std::size_t packed_bit_bytes(std::size_t bit_count) noexcept {
    return (bit_count + 7) / 8;
}
// Packs `bits` into packed_bit_bytes(bits.size()) bytes of `out` (BufferTooSmall otherwise).
EncodeResult pack_bits(std::span<const bool> bits, MutableBytes out) noexcept;
// Same, from one byte per bit (any non-zero byte is ON).
EncodeResult pack_bit_bytes(std::span<const std::uint8_t> bits, MutableBytes out) noexcept;
// Unpacks the first out.size() bits; false when `packed` holds fewer bits.
bool unpack_bits(Bytes packed, std::span<bool> out) noexcept;
// Bit `index` of a packed array (index must be < packed.size() * 8).
constexpr bool bit_at(Bytes packed, std::size_t index) noexcept {
    return (packed[index / 8] >> (index % 8)) & 1u;
}
// True when every bit from `bit_count` to the end of the last byte is zero.
bool padding_is_zero(Bytes packed, std::size_t bit_count) noexcept;

// ---- Numbers over several registers.
//
// The value's bytes, most significant first, are A B C D (E F G H for 64 bits).
//   ABCD: big-endian words, big-endian bytes (the Modbus default): regs = AB CD
//   CDAB: words swapped ("low word first"):                       regs = CD AB
//   BADC: bytes swapped inside each word:                         regs = BA DC
//   DCBA: both (the value little-endian):                         regs = DC BA
// For 64 bits the names generalise: CDAB = word order reversed (GH EF CD AB), BADC = bytes
// swapped in each word (BA DC FE HG), DCBA = both (HG FE DC BA).
enum class WordOrder : std::uint8_t { ABCD, CDAB, BADC, DCBA };

std::string_view word_order_name(WordOrder order) noexcept;  // "ABCD"
// Accepts the names case-insensitively; false when unknown.
bool word_order_from_name(std::string_view name, WordOrder& out) noexcept;

using Registers2 = std::array<std::uint16_t, 2>;
using Registers4 = std::array<std::uint16_t, 4>;

Registers2 registers_from_u32(std::uint32_t value, WordOrder order) noexcept;
Registers2 registers_from_i32(std::int32_t value, WordOrder order) noexcept;
Registers2 registers_from_f32(float value, WordOrder order) noexcept;
Registers4 registers_from_u64(std::uint64_t value, WordOrder order) noexcept;
Registers4 registers_from_i64(std::int64_t value, WordOrder order) noexcept;
Registers4 registers_from_f64(double value, WordOrder order) noexcept;

std::uint32_t u32_from_registers(std::span<const std::uint16_t, 2> regs, WordOrder order) noexcept;
std::int32_t i32_from_registers(std::span<const std::uint16_t, 2> regs, WordOrder order) noexcept;
float f32_from_registers(std::span<const std::uint16_t, 2> regs, WordOrder order) noexcept;
std::uint64_t u64_from_registers(std::span<const std::uint16_t, 4> regs, WordOrder order) noexcept;
std::int64_t i64_from_registers(std::span<const std::uint16_t, 4> regs, WordOrder order) noexcept;
double f64_from_registers(std::span<const std::uint16_t, 4> regs, WordOrder order) noexcept;

// ---- Tables and Modicon reference numbers.

std::string_view table_name(Table table) noexcept;  // "holding_registers"
bool table_from_name(std::string_view name, Table& out) noexcept;
// True for the two 1-bit tables.
constexpr bool is_bit_table(Table table) noexcept {
    return table == Table::Coils || table == Table::DiscreteInputs;
}

struct Reference {
    Table table = Table::Coils;
    std::uint16_t offset = 0;  // 0-based address on the wire
    friend constexpr bool operator==(const Reference&, const Reference&) = default;
};

// Parses "0xxxx" coils, "1xxxx" discrete inputs, "3xxxx" input registers, "4xxxx" holding
// registers (5 digits, xxxx = 0001..9999) or the 6-digit forms (xxxxx = 00001..65536).
// Offset = number - 1. False for anything else.
bool parse_reference(std::string_view text, Reference& out) noexcept;
// 5 digits while the number fits (offset < 9999), else 6 digits; or always 6 digits.
std::string format_reference(Reference ref, bool six_digits = false);

// ---- Hex text ("01 03 00 00 00 0A C5 CD", "0103000A", "01:03", "0x01,0x03").

struct HexParseResult {
    std::size_t size = 0;  // bytes written
    CodecError error = CodecError::Ok;
    std::size_t position = 0;  // character index of the error
    constexpr bool ok() const noexcept { return error == CodecError::Ok; }
};

// Parses hex digit pairs, case-insensitive. Spaces, tabs, CR/LF, ':', '-' and ',' separate
// groups; a group may start with "0x". Errors: Empty (no digits), BadHexDigit, OddHexLength
// (a group with an odd number of digits), BufferTooSmall.
HexParseResult parse_hex(std::string_view text, MutableBytes out) noexcept;
// Uppercase hex, bytes separated by `separator` ('\0' for none).
std::string format_hex(Bytes bytes, char separator = ' ');

}  // namespace mbstorm::codec
