// Internal helpers shared by the PDU encoders and decoders (not part of the public API).
#pragma once

#include <cstddef>
#include <cstdint>

#include "codec/bytes.hpp"
#include "codec/error.hpp"
#include "codec/exception_code.hpp"
#include "codec/limits.hpp"

namespace mbstorm::codec::detail {

// Ok when `have == want`, otherwise whether bytes are missing or left over.
constexpr CodecError exact_size(std::size_t have, std::size_t want) noexcept {
    if (have < want) return CodecError::Truncated;
    if (have > want) return CodecError::TrailingBytes;
    return CodecError::Ok;
}

// The last addressed item must be 0xFFFF at most.
constexpr bool range_fits(std::uint16_t address, std::uint16_t quantity) noexcept {
    return std::uint32_t{address} + quantity <= 0x10000u;
}

// One unsigned compare: lo <= v <= hi.
constexpr bool in_range(unsigned v, unsigned lo, unsigned hi) noexcept {
    return v - lo <= hi - lo;
}

constexpr std::size_t packed_coil_bytes(std::uint16_t quantity) noexcept {
    return (std::size_t{quantity} + 7u) / 8u;
}

// What the data field of an FC08 sub-function looks like.
enum class DiagnosticData : std::uint8_t { Unknown, AnyLength, OneWord };
constexpr DiagnosticData diagnostic_data(std::uint16_t sub_function) noexcept {
    if (sub_function == 0x0000) return DiagnosticData::AnyLength;  // Return Query Data echoes
    if (sub_function <= 0x0004) return DiagnosticData::OneWord;
    if (in_range(sub_function, 0x000A, 0x0012) || sub_function == 0x0014) {
        return DiagnosticData::OneWord;
    }
    return DiagnosticData::Unknown;  // 0x0013 is reserved, the rest undefined
}

// Verdict on a block of FC14/15 sub-requests: the error and the exception a server owes.
struct FileCheck {
    CodecError error = CodecError::Ok;
    ExceptionCode exception = ExceptionCode::None;
};
// Checks FC14 (`with_data` false) or FC15 sub-requests that exactly fill `sub_requests`.
// Shape and size problems (03) are reported before reference/file/record problems (02).
FileCheck check_file_sub_requests(Bytes sub_requests, bool with_data) noexcept;

}  // namespace mbstorm::codec::detail
