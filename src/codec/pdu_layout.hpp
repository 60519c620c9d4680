// The fields of each request and response shape in wire order, with the names `decode` and
// `encode` show them by. They live beside the shapes so that a new shape is described once,
// here, and the explainers walk the description instead of restating each function's layout.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

#include "codec/function_code.hpp"

namespace mbstorm::codec {

// How many bytes a field takes and how its value reads.
enum class FieldKind : std::uint8_t {
    Byte,                     // one byte, a number
    Word,                     // two bytes big-endian, a number
    CoilValue,                // FC 05's two bytes: 0xFF00 ON, 0x0000 OFF
    MeiType,                  // a request's MEI type byte (0x0E: read device identification)
    MoreFollows,              // one byte, 0x00 the last answer, 0xFF more follow
    Registers,                // `count` words, one row each
    PackedBits,               // `count` bytes of packed bits, one row each
    Rest,                     // every byte left, in one row
    FileSubRequests,          // FC 14's sub-requests: reference type, file, record, length
    FileSubRequestsWithData,  // FC 15's: the same, each followed by its record data
    FileSubResponses,         // FC 14's answers: length, reference type, data
    DeviceIdObjects,          // FC 2B/0E's objects: id, length, value
};

// Where the number of items of a Registers or PackedBits field comes from: the decoded
// Request's or Response's `payload` size (in bytes or in words) or one of its counts.
enum class FieldCount : std::uint8_t {
    One,
    PayloadBytes,
    PayloadWords,
    Quantity,
    WriteQuantity,
    FifoCount
};

// How the items of a Registers or PackedBits field are numbered: 1, 2, ... or by the address
// each one has (the request's start address, or FC 17's write address).
enum class FieldNumbering : std::uint8_t { Ordinal, FromAddress, FromWriteAddress };

struct PduField {
    std::string_view name;
    FieldKind kind;
    FieldCount count = FieldCount::One;
    FieldNumbering numbering = FieldNumbering::Ordinal;
};

struct PduLayout {
    std::span<const PduField> fields;  // after the function code
    // PDU offset where the decoder's `payload` begins when it must be read without decoding
    // (a PDU the decoder refuses); 0 when no field of the layout counts or walks the payload.
    std::size_t payload_at = 0;
};

// The fields of a request (a normal response) of function `f`.
PduLayout request_layout(const FunctionInfo& f) noexcept;
PduLayout response_layout(const FunctionInfo& f) noexcept;

// Bytes a field of fixed width takes (Byte, Word, CoilValue, MeiType, MoreFollows); 0 for the
// fields whose width depends on the PDU.
std::size_t fixed_width(FieldKind kind) noexcept;

}  // namespace mbstorm::codec
