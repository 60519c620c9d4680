// RTU framing: slicing-by-8 CRC-16/MODBUS, frame encode/decode, length inference.
#include "codec/rtu.hpp"

#include <array>
#include <bit>
#include <cstring>

#include "codec/function_code.hpp"

namespace mbstorm::codec {

namespace {

constexpr std::uint16_t kCrcPoly = 0xA001;  // 0x8005 bit-reversed
constexpr std::size_t kSlices = 8;
using CrcTables = std::array<std::array<std::uint16_t, 256>, kSlices>;

// tables[k][b]: the CRC contribution of byte b followed by k zero bytes, which lets the
// main loop fold eight bytes per step with independent table lookups.
constexpr CrcTables make_crc_tables() {
    CrcTables t{};
    for (unsigned b = 0; b < 256; ++b) {
        std::uint16_t crc = static_cast<std::uint16_t>(b);
        for (int bit = 0; bit < 8; ++bit) {
            crc = static_cast<std::uint16_t>((crc & 1u) ? (crc >> 1) ^ kCrcPoly : crc >> 1);
        }
        t[0][b] = crc;
    }
    for (std::size_t k = 1; k < kSlices; ++k) {
        for (unsigned b = 0; b < 256; ++b) {
            const std::uint16_t prev = t[k - 1][b];
            t[k][b] = static_cast<std::uint16_t>((prev >> 8) ^ t[0][prev & 0xFFu]);
        }
    }
    return t;
}

constexpr CrcTables kCrcTables = make_crc_tables();

constexpr RtuLength known(std::size_t size) noexcept {
    if (size > limits::kMaxRtuAdu) return {RtuLength::Status::TooLong, size};
    return {RtuLength::Status::Known, size};
}
constexpr RtuLength need(std::size_t size) noexcept {
    return {RtuLength::Status::NeedMore, size};
}
constexpr RtuLength unknown() noexcept {
    return {RtuLength::Status::Unknown, 0};
}

// Frame = fixed part up to and including an 8-bit byte count at `count_at`, then that many
// bytes, then the CRC.
RtuLength with_byte_count(Bytes head, std::size_t count_at) noexcept {
    if (head.size() <= count_at) return need(count_at + 1);
    return known(count_at + 1 + head[count_at] + 2);
}

// FC2B/0E response: 8 bytes of header (address included), then `object_count` objects of
// (id, length, value[length]).
RtuLength device_id_response_length(Bytes head) noexcept {
    constexpr std::size_t kObjectsAt = 8;  // addr fc mei code conformity more next count
    if (head.size() < kObjectsAt) return need(kObjectsAt);
    const unsigned objects = head[7];
    std::size_t pos = kObjectsAt;
    for (unsigned i = 0; i < objects; ++i) {
        if (head.size() < pos + 2) return need(pos + 2);
        pos += 2 + head[pos + 1];
        // Stop walking as soon as the frame cannot fit, so `pos` stays small.
        if (pos + 2 > limits::kMaxRtuAdu) return {RtuLength::Status::TooLong, pos + 2};
    }
    return known(pos + 2);
}

}  // namespace

std::uint16_t crc16(Bytes data, std::uint16_t crc) noexcept {
    const std::uint8_t* p = data.data();
    std::size_t n = data.size();
    const auto& t = kCrcTables;
    while (n >= kSlices) {
        std::uint32_t lo;
        std::uint32_t hi;
        std::memcpy(&lo, p, 4);
        std::memcpy(&hi, p + 4, 4);
        // Byte order independent: pick bytes by shifting a little-endian view.
        if constexpr (std::endian::native == std::endian::big) {
            lo = __builtin_bswap32(lo);
            hi = __builtin_bswap32(hi);
        }
        lo ^= crc;
        crc = static_cast<std::uint16_t>(
            t[7][lo & 0xFF] ^ t[6][(lo >> 8) & 0xFF] ^ t[5][(lo >> 16) & 0xFF] ^ t[4][lo >> 24] ^
            t[3][hi & 0xFF] ^ t[2][(hi >> 8) & 0xFF] ^ t[1][(hi >> 16) & 0xFF] ^ t[0][hi >> 24]);
        p += kSlices;
        n -= kSlices;
    }
    while (n-- > 0) crc = static_cast<std::uint16_t>((crc >> 8) ^ t[0][(crc ^ *p++) & 0xFF]);
    return crc;
}

EncodeResult encode_rtu_frame(std::uint8_t address, Bytes pdu, MutableBytes out) noexcept {
    if (pdu.empty() || pdu.size() > limits::kMaxPdu) return {0, CodecError::InvalidArgument};
    const std::size_t total = 1 + pdu.size() + 2;
    if (out.size() < total) return {0, CodecError::BufferTooSmall};
    std::uint8_t* p = out.data();
    if (pdu.data() != p + 1) std::memmove(p + 1, pdu.data(), pdu.size());
    p[0] = address;
    const std::uint16_t crc = crc16(Bytes(p, 1 + pdu.size()));
    p[total - 2] = static_cast<std::uint8_t>(crc);
    p[total - 1] = static_cast<std::uint8_t>(crc >> 8);
    return {total, CodecError::Ok};
}

CodecError decode_rtu_frame(Bytes adu, RtuFrame& out) noexcept {
    out = RtuFrame{};
    if (adu.empty()) return CodecError::Empty;
    if (adu.size() < kMinRtuAdu) return CodecError::Truncated;
    if (adu.size() > limits::kMaxRtuAdu) return CodecError::FrameTooLong;
    const std::size_t body = adu.size() - 2;
    const std::uint16_t wire = static_cast<std::uint16_t>(adu[body] | (adu[body + 1] << 8));
    if (crc16(adu.first(body)) != wire) return CodecError::BadCrc;
    out.address = adu[0];
    out.pdu = adu.subspan(1, body - 1);
    out.adu = adu;
    return CodecError::Ok;
}

RtuLength rtu_request_length(Bytes head) noexcept {
    if (head.size() < 2) return need(2);
    switch (static_cast<FunctionCode>(head[1])) {
        // Two 16-bit fields: address + quantity, address + value, or sub-function + data.
        case FunctionCode::ReadCoils:
        case FunctionCode::ReadDiscreteInputs:
        case FunctionCode::ReadHoldingRegisters:
        case FunctionCode::ReadInputRegisters:
        case FunctionCode::WriteSingleCoil:
        case FunctionCode::WriteSingleRegister:
        case FunctionCode::Diagnostics:
            return known(8);
        // Function code only.
        case FunctionCode::ReadExceptionStatus:
        case FunctionCode::GetCommEventCounter:
        case FunctionCode::GetCommEventLog:
        case FunctionCode::ReportServerId:
            return known(4);
        // Address, quantity, then a byte count.
        case FunctionCode::WriteMultipleCoils:
        case FunctionCode::WriteMultipleRegisters:
            return with_byte_count(head, 6);
        // A byte count right after the function code.
        case FunctionCode::ReadFileRecord:
        case FunctionCode::WriteFileRecord:
            return with_byte_count(head, 2);
        // Address, AND mask, OR mask.
        case FunctionCode::MaskWriteRegister:
            return known(10);
        // Read address/quantity, write address/quantity, then a byte count.
        case FunctionCode::ReadWriteMultipleRegisters:
            return with_byte_count(head, 10);
        // FIFO pointer address.
        case FunctionCode::ReadFifoQueue:
            return known(6);
        case FunctionCode::EncapsulatedInterface:
            if (head.size() < 3) return need(3);
            if (head[2] == kMeiReadDeviceId) return known(7);  // mei, code, object id
            return unknown();
    }
    return unknown();
}

RtuLength rtu_response_length(Bytes head) noexcept {
    if (head.size() < 2) return need(2);
    const std::uint8_t fc = head[1];
    if (fc & kExceptionBit) return known(5);  // address, fc|0x80, code, CRC
    switch (static_cast<FunctionCode>(fc)) {
        // A byte count right after the function code.
        case FunctionCode::ReadCoils:
        case FunctionCode::ReadDiscreteInputs:
        case FunctionCode::ReadHoldingRegisters:
        case FunctionCode::ReadInputRegisters:
        case FunctionCode::GetCommEventLog:
        case FunctionCode::ReportServerId:
        case FunctionCode::ReadFileRecord:
        case FunctionCode::WriteFileRecord:
        case FunctionCode::ReadWriteMultipleRegisters:
            return with_byte_count(head, 2);
        // Two 16-bit fields echoed or reported.
        case FunctionCode::WriteSingleCoil:
        case FunctionCode::WriteSingleRegister:
        case FunctionCode::Diagnostics:
        case FunctionCode::GetCommEventCounter:
        case FunctionCode::WriteMultipleCoils:
        case FunctionCode::WriteMultipleRegisters:
            return known(8);
        // Exception status byte.
        case FunctionCode::ReadExceptionStatus:
            return known(5);
        // Address, AND mask, OR mask echoed.
        case FunctionCode::MaskWriteRegister:
            return known(10);
        // 16-bit byte count (FIFO count + values).
        case FunctionCode::ReadFifoQueue:
            if (head.size() < 4) return need(4);
            return known(4 + load_be16(head.data() + 2) + 2u);
        case FunctionCode::EncapsulatedInterface:
            if (head.size() < 3) return need(3);
            if (head[2] == kMeiReadDeviceId) return device_id_response_length(head);
            return unknown();
    }
    return unknown();
}

}  // namespace mbstorm::codec
