// Byte views and big-endian helpers shared by every codec file.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

namespace mbstorm::codec {

using Bytes = std::span<const std::uint8_t>;
using MutableBytes = std::span<std::uint8_t>;

// Modbus is big-endian on the wire for every 16-bit field.
constexpr std::uint16_t load_be16(const std::uint8_t* p) noexcept {
    return static_cast<std::uint16_t>((p[0] << 8) | p[1]);
}
constexpr void store_be16(std::uint8_t* p, std::uint16_t v) noexcept {
    p[0] = static_cast<std::uint8_t>(v >> 8);
    p[1] = static_cast<std::uint8_t>(v);
}

}  // namespace mbstorm::codec
