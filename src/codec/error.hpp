// Every way a frame or PDU can be malformed, as a value (hot paths never throw).
#pragma once

#include <cstdint>
#include <string_view>

namespace mbstorm::codec {

enum class CodecError : std::uint8_t {
    Ok = 0,
    // PDU level
    Empty,                   // zero bytes where a PDU was expected
    Truncated,               // fewer bytes than the function code needs
    TrailingBytes,           // more bytes than the function code needs
    UnsupportedFunction,     // function code the codec does not know
    QuantityOutOfRange,      // quantity outside the function's limits
    ByteCountMismatch,       // byte count field disagrees with the quantity or the PDU length
    AddressOverflow,         // address + quantity runs past 0xFFFF
    InvalidCoilValue,        // FC05 value other than 0x0000 / 0xFF00
    UnsupportedSubFunction,  // FC08 sub-function or FC2B MEI type unknown
    InvalidReferenceType,    // FC14/15 sub-request reference type other than 6
    InvalidDeviceIdCode,     // FC2B/0E read device id code outside 1..4
    InvalidExceptionCode,    // exception response with a code of 0
    BufferTooSmall,          // encoder: the caller's buffer cannot hold the result
    InvalidArgument,         // encoder: fields that cannot form a valid PDU
    // MBAP (TCP)
    BadProtocolId,   // protocol identifier != 0
    LengthZero,      // MBAP length field 0
    LengthOne,       // MBAP length field 1 (unit id only, no function code)
    LengthTooLong,   // MBAP length field > 254
    LengthMismatch,  // MBAP length disagrees with the bytes given
    // RTU
    BadCrc,
    // ASCII
    MissingStart,  // no leading ':'
    MissingEnd,    // no trailing CR LF
    BadHexDigit,
    OddHexLength,
    BadLrc,
    FrameTooLong,
};

std::string_view error_name(CodecError e) noexcept;         // "truncated"
std::string_view error_description(CodecError e) noexcept;  // one readable sentence fragment

}  // namespace mbstorm::codec
