// Names and readable descriptions of every codec error.
#include "codec/error.hpp"

namespace mbstorm::codec {

std::string_view error_name(CodecError e) noexcept {
    switch (e) {
        case CodecError::Ok:
            return "ok";
        case CodecError::Empty:
            return "empty";
        case CodecError::Truncated:
            return "truncated";
        case CodecError::TrailingBytes:
            return "trailing_bytes";
        case CodecError::UnsupportedFunction:
            return "unsupported_function";
        case CodecError::QuantityOutOfRange:
            return "quantity_out_of_range";
        case CodecError::ByteCountMismatch:
            return "byte_count_mismatch";
        case CodecError::AddressOverflow:
            return "address_overflow";
        case CodecError::InvalidCoilValue:
            return "invalid_coil_value";
        case CodecError::UnsupportedSubFunction:
            return "unsupported_sub_function";
        case CodecError::InvalidReferenceType:
            return "invalid_reference_type";
        case CodecError::InvalidDeviceIdCode:
            return "invalid_device_id_code";
        case CodecError::InvalidExceptionCode:
            return "invalid_exception_code";
        case CodecError::BufferTooSmall:
            return "buffer_too_small";
        case CodecError::InvalidArgument:
            return "invalid_argument";
        case CodecError::BadProtocolId:
            return "bad_protocol_id";
        case CodecError::LengthZero:
            return "length_zero";
        case CodecError::LengthOne:
            return "length_one";
        case CodecError::LengthTooLong:
            return "length_too_long";
        case CodecError::LengthMismatch:
            return "length_mismatch";
        case CodecError::BadCrc:
            return "bad_crc";
        case CodecError::MissingStart:
            return "missing_start";
        case CodecError::MissingEnd:
            return "missing_end";
        case CodecError::BadHexDigit:
            return "bad_hex_digit";
        case CodecError::OddHexLength:
            return "odd_hex_length";
        case CodecError::BadLrc:
            return "bad_lrc";
        case CodecError::FrameTooLong:
            return "frame_too_long";
    }
    return "unknown_error";
}

std::string_view error_description(CodecError e) noexcept {
    switch (e) {
        case CodecError::Ok:
            return "no error";
        case CodecError::Empty:
            return "no bytes where a PDU was expected";
        case CodecError::Truncated:
            return "fewer bytes than the function code needs";
        case CodecError::TrailingBytes:
            return "more bytes than the function code needs";
        case CodecError::UnsupportedFunction:
            return "function code not supported";
        case CodecError::QuantityOutOfRange:
            return "quantity outside the function's limits";
        case CodecError::ByteCountMismatch:
            return "byte count disagrees with the quantity or the PDU length";
        case CodecError::AddressOverflow:
            return "address range runs past the end of the table";
        case CodecError::InvalidCoilValue:
            return "coil value other than 0xFF00 or 0x0000";
        case CodecError::UnsupportedSubFunction:
            return "sub-function or MEI type not supported";
        case CodecError::InvalidReferenceType:
            return "file reference type other than 6";
        case CodecError::InvalidDeviceIdCode:
            return "read device id code outside 1..4";
        case CodecError::InvalidExceptionCode:
            return "exception response with code 0";
        case CodecError::BufferTooSmall:
            return "output buffer too small";
        case CodecError::InvalidArgument:
            return "fields cannot form a valid PDU";
        case CodecError::BadProtocolId:
            return "MBAP protocol identifier is not 0";
        case CodecError::LengthZero:
            return "MBAP length field is 0";
        case CodecError::LengthOne:
            return "MBAP length field is 1 (no function code)";
        case CodecError::LengthTooLong:
            return "MBAP length field exceeds 254";
        case CodecError::LengthMismatch:
            return "MBAP length disagrees with the bytes received";
        case CodecError::BadCrc:
            return "RTU CRC mismatch";
        case CodecError::MissingStart:
            return "ASCII frame does not start with ':'";
        case CodecError::MissingEnd:
            return "ASCII frame does not end with CR LF";
        case CodecError::BadHexDigit:
            return "ASCII frame holds a non-hex character";
        case CodecError::OddHexLength:
            return "ASCII frame has an odd number of hex digits";
        case CodecError::BadLrc:
            return "ASCII LRC mismatch";
        case CodecError::FrameTooLong:
            return "frame longer than the protocol allows";
    }
    return "unknown error";
}

}  // namespace mbstorm::codec
