// Modbus RTU framing: address + PDU + CRC-16 (low byte first), and frame length inference,
// since RTU carries no length field and a reader must know when a frame is complete.
#pragma once

#include <cstddef>
#include <cstdint>

#include "codec/bytes.hpp"
#include "codec/error.hpp"
#include "codec/limits.hpp"
#include "codec/pdu.hpp"

namespace mbstorm::codec {

// The shortest RTU frame: address, function code, CRC.
inline constexpr std::size_t kMinRtuAdu = 4;

// CRC-16/MODBUS (reflected polynomial 0xA001, initial value 0xFFFF). Pass a previous result
// as `crc` to continue over several pieces.
std::uint16_t crc16(Bytes data, std::uint16_t crc = 0xFFFF) noexcept;

// One RTU ADU: views into the decoded bytes.
struct RtuFrame {
    std::uint8_t address = 0;
    Bytes pdu;  // function code + data
    Bytes adu;  // address + PDU + CRC
};

// Writes address + PDU + CRC (low byte, then high byte) into `out`. The PDU may already sit
// at out[1..] (no copy then). InvalidArgument for an empty or oversized PDU.
EncodeResult encode_rtu_frame(std::uint8_t address, Bytes pdu, MutableBytes out) noexcept;

// Decodes exactly one ADU: Empty, Truncated (< 4 bytes), FrameTooLong (> 256), BadCrc or Ok.
CodecError decode_rtu_frame(Bytes adu, RtuFrame& out) noexcept;

// Answer of the length inference functions below.
struct RtuLength {
    enum class Status : std::uint8_t {
        Known,     // `size` is the whole ADU length, address and CRC included
        NeedMore,  // read until `size` bytes are present, then ask again
        Unknown,   // the function code (or MEI type) has no length rule the codec knows
        TooLong,   // the byte count fields describe a frame longer than 256 bytes
    };
    Status status = Status::NeedMore;
    std::size_t size = 0;
};

// Length of the request frame that starts with `head` (address first). Needs at most the
// bytes up to the request's byte count field.
RtuLength rtu_request_length(Bytes head) noexcept;

// Length of the response frame that starts with `head`. Exception responses are 5 bytes;
// FC2B/0E responses are walked object by object.
RtuLength rtu_response_length(Bytes head) noexcept;

}  // namespace mbstorm::codec
