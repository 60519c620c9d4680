// Quantity and size limits from the Modbus Application Protocol Specification v1.1b3.
// One place for these facts: every other layer asks here.
#pragma once

#include <cstddef>
#include <cstdint>

namespace mbstorm::codec::limits {

inline constexpr std::size_t kMaxPdu = 253;           // function code + data
inline constexpr std::size_t kMbapHeader = 7;         // tid(2) pid(2) length(2) unit(1)
inline constexpr std::size_t kMaxTcpAdu = 260;        // MBAP header + PDU
inline constexpr std::size_t kMaxRtuAdu = 256;        // address + PDU + CRC
inline constexpr std::size_t kMaxAsciiAdu = 513;      // ':' + 2*(addr+PDU+LRC) + CRLF
inline constexpr std::uint16_t kMaxMbapLength = 254;  // unit id + PDU

inline constexpr std::uint16_t kMaxReadBits = 2000;         // FC01/02 (0x7D0)
inline constexpr std::uint16_t kMaxReadRegisters = 125;     // FC03/04 (0x7D)
inline constexpr std::uint16_t kMaxWriteCoils = 1968;       // FC0F (0x7B0)
inline constexpr std::uint16_t kMaxWriteRegisters = 123;    // FC10 (0x7B)
inline constexpr std::uint16_t kMaxRwReadRegisters = 125;   // FC17 read part (0x7D)
inline constexpr std::uint16_t kMaxRwWriteRegisters = 121;  // FC17 write part (0x79)
inline constexpr std::uint16_t kMaxFifoCount = 31;          // FC18
inline constexpr std::uint16_t kCoilOn = 0xFF00;            // FC05
inline constexpr std::uint16_t kCoilOff = 0x0000;
inline constexpr std::uint8_t kFileReferenceType = 6;       // FC14/15
inline constexpr std::uint8_t kMinFileRequestBytes = 0x07;  // FC14 byte count range
inline constexpr std::uint8_t kMaxFileRequestBytes = 0xF5;
inline constexpr std::uint16_t kMaxFileRecordNumber = 0x270F;
inline constexpr std::uint16_t kMinFileNumber = 0x0001;   // FC14/15 sub-request file number
inline constexpr std::uint8_t kMinFileWriteBytes = 0x09;  // FC15 request data length range
inline constexpr std::uint8_t kMaxFileWriteBytes = 0xFB;
inline constexpr std::uint8_t kMaxFileResponseBytes = 0xF5;  // FC14 response data length
inline constexpr std::uint8_t kMaxCommEventBytes = 64;       // FC0C events in the log
inline constexpr std::uint8_t kMinDeviceIdCode = 1;          // FC2B/0E: basic stream
inline constexpr std::uint8_t kMaxDeviceIdCode = 4;          // FC2B/0E: one specific object

// A quantity a request may ask for; max == 0: none. codec::quantity_range(fc) gives it per
// function (function_code.hpp).
struct QuantityRange {
    std::uint16_t min = 0;
    std::uint16_t max = 0;
};

}  // namespace mbstorm::codec::limits
