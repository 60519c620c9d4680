// Values as `mbstorm read` prints them and `mbstorm write` takes them: registers (or bits)
// seen as u16, i16, u32, i32, u64, i64, f32, f64, string or bits in one of the four word/byte
// orders the codec knows.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "codec/values.hpp"
#include "util/error.hpp"

namespace mbstorm::cli {

enum class ValueType : std::uint8_t { U16, I16, U32, I32, U64, I64, F32, F64, String, Bits };

inline constexpr std::string_view kValueTypeNames =
    "u16, i16, u32, i32, u64, i64, f32, f64, "
    "string, bits";

bool value_type_from_name(std::string_view name, ValueType& out) noexcept;
std::string_view value_type_name(ValueType type) noexcept;

// Registers one value of `type` takes (string: 1 per two characters, bits: 1 per register).
std::size_t registers_per_value(ValueType type) noexcept;

// One printed value: the address of its first register (or bit) and its text.
struct TypedValue {
    std::uint16_t address = 0;
    std::string text;
    double number = 0;      // for JSON: numeric types
    bool is_number = true;  // false: string and register bits are JSON strings
};

// Registers -> values, `first_address` being the address of regs[0]. A string is one value.
std::vector<TypedValue> values_from_registers(std::span<const std::uint16_t> regs,
                                              std::uint16_t first_address, ValueType type,
                                              codec::WordOrder order);

// Text -> registers for a write, or what is wrong with which value (InvalidInput).
Error registers_from_text(const std::vector<std::string>& texts, ValueType type,
                          codec::WordOrder order, std::vector<std::uint16_t>& out);

// "1", "0", "on", "off", "true", "false" -> a bit; false when it is none of those.
bool parse_bit(std::string_view text, bool& out) noexcept;

}  // namespace mbstorm::cli
