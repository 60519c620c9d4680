// Packing of io_uring user_data: which operation completed, for which connection slot, and
// which incarnation of that slot (so a late completion for a closed, reused slot is ignored).
//
//   bits 63..56  op     (caller-defined, 0..255)
//   bits 55..32  generation (24 bits, wraps)
//   bits 31..0   index  (connection slot or any other id)
#pragma once

#include <cstdint>
#include <type_traits>

namespace mbstorm::net {

inline constexpr std::uint32_t kGenerationMask = 0xFF'FFFF;

struct UserData {
    std::uint8_t op = 0;
    std::uint32_t generation = 0;  // only the low 24 bits are kept
    std::uint32_t index = 0;
};

constexpr std::uint64_t encode_user_data(std::uint8_t op, std::uint32_t index,
                                         std::uint32_t generation) noexcept {
    return (static_cast<std::uint64_t>(op) << 56) |
           (static_cast<std::uint64_t>(generation & kGenerationMask) << 32) | index;
}

// The same for a worker's own operation enum (an `enum class Op : std::uint8_t`).
template <class Op>
requires std::is_enum_v<Op>
constexpr std::uint64_t encode_user_data(Op op, std::uint32_t index,
                                         std::uint32_t generation) noexcept {
    return encode_user_data(static_cast<std::uint8_t>(op), index, generation);
}

constexpr UserData decode_user_data(std::uint64_t v) noexcept {
    return UserData{static_cast<std::uint8_t>(v >> 56),
                    static_cast<std::uint32_t>(v >> 32) & kGenerationMask,
                    static_cast<std::uint32_t>(v)};
}

constexpr std::uint32_t next_generation(std::uint32_t g) noexcept {
    return (g + 1) & kGenerationMask;
}

}  // namespace mbstorm::net
