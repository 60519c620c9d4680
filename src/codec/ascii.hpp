// Modbus ASCII framing: ':' + hex of (address + PDU + LRC) + CR LF.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "codec/bytes.hpp"
#include "codec/error.hpp"
#include "codec/limits.hpp"
#include "codec/pdu.hpp"

namespace mbstorm::codec {

// Longitudinal redundancy check: two's complement of the 8-bit sum of `data`.
std::uint8_t lrc(Bytes data) noexcept;

// One decoded ASCII frame: views into the caller's binary buffer.
struct AsciiFrame {
    std::uint8_t address = 0;
    Bytes pdu;     // function code + data
    Bytes binary;  // address + PDU + LRC, as decoded
};

// Decodes one complete frame (the whole of `text`, CR LF included) into `buf`, which needs
// (text.size() - 3) / 2 bytes. Hex digits may be upper or lower case. Errors, first match
// wins: Empty, MissingStart, FrameTooLong (> 513 characters), MissingEnd, OddHexLength,
// BadHexDigit, Truncated (fewer than address + function + LRC), BufferTooSmall, BadLrc.
CodecError decode_ascii_frame(Bytes text, MutableBytes buf, AsciiFrame& out) noexcept;
inline CodecError decode_ascii_frame(std::string_view text, MutableBytes buf,
                                     AsciiFrame& out) noexcept {
    return decode_ascii_frame(
        Bytes(reinterpret_cast<const std::uint8_t*>(text.data()), text.size()), buf, out);
}

// Characters an encoded frame of a `pdu_size`-byte PDU takes.
constexpr std::size_t ascii_frame_size(std::size_t pdu_size) noexcept {
    return 1 + 2 * (1 + pdu_size + 1) + 2;
}

// Writes ':' + uppercase hex + CR LF into `out`. InvalidArgument for an empty or oversized
// PDU, BufferTooSmall when `out` cannot hold ascii_frame_size(pdu.size()) bytes. `pdu` must
// not overlap `out` (the text is twice as long as the bytes).
EncodeResult encode_ascii_frame(std::uint8_t address, Bytes pdu, MutableBytes out) noexcept;

}  // namespace mbstorm::codec
