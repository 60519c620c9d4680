// Hex digit conversion shared by the ASCII framing and the CLI hex parser.
#pragma once

#include <array>
#include <cstdint>

namespace mbstorm::codec::hex {

inline constexpr std::uint8_t kNotHex = 0xFF;

namespace detail {
constexpr std::array<std::uint8_t, 256> make_digit_table() {
    std::array<std::uint8_t, 256> t{};
    for (auto& v : t) v = kNotHex;
    for (int c = 0; c < 10; ++c) t['0' + c] = static_cast<std::uint8_t>(c);
    for (int c = 0; c < 6; ++c) {
        t['A' + c] = static_cast<std::uint8_t>(10 + c);
        t['a' + c] = static_cast<std::uint8_t>(10 + c);
    }
    return t;
}
inline constexpr std::array<std::uint8_t, 256> kDigitValue = make_digit_table();
}  // namespace detail

// 0..15 for '0'-'9', 'A'-'F', 'a'-'f'; kNotHex otherwise.
constexpr std::uint8_t digit_value(std::uint8_t c) noexcept {
    return detail::kDigitValue[c];
}

inline constexpr char kUpperDigits[] = "0123456789ABCDEF";

}  // namespace mbstorm::codec::hex
