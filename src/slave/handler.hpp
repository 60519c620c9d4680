// The slave's request handler: a pure function of (request PDU, data model) that writes the
// response PDU into the caller's buffer. No allocation, no exceptions, no I/O, no clock.
// The server, the fuzz harnesses and the tests all call this one function.
//
// Function codes served: 01-08, 0B, 0C, 0F, 10, 11, 14-18, 2B/0E. Anything else -> 01.
// Exception precedence follows the spec's state diagrams:
//   01 unsupported function (or FC08 sub-function / FC2B MEI type)
//   03 bad quantity, byte count, coil value or malformed PDU (from codec::decode_request)
//   02 address range outside the configured table (after the codec's own 0xFFFF check)
//   04 failure while executing (not produced by this model, kept for completeness)
// FC08 sub-functions: 00 echo, 01 restart (clears counters; data 0xFF00 also clears the event
// log), 02 diagnostic register (always 0), 0A clear counters, 0B-12 counters, 14 clear overrun.
// 03 (ASCII delimiter) and 04 (listen-only) are serial-line only and answer 01.
// FC0B/0C do not count themselves as comm events (they only fetch).
#pragma once

#include <cstddef>
#include <cstdint>

#include "codec/bytes.hpp"
#include "codec/exception_code.hpp"
#include "slave/data_model.hpp"

namespace mbstorm::slave {

enum class Outcome : std::uint8_t {
    Response,    // a normal response of `size` bytes
    Exception,   // an exception response (2 bytes); see `exception`
    NoResponse,  // nothing to send (empty PDU, broadcast, ignored unknown unit, buffer too small)
};

struct HandleResult {
    std::uint32_t size = 0;  // bytes written (32 bits: keeps the struct in one register)
    Outcome outcome = Outcome::NoResponse;
    codec::ExceptionCode exception = codec::ExceptionCode::None;
    std::uint8_t function = 0;  // the request's function code byte (0 for an empty PDU)
    bool wrote = false;         // the request changed the model
};

// The output buffer must hold at least kMinOutput bytes; a smaller one gives NoResponse.
inline constexpr std::size_t kMinOutput = 253;

// Handles one request for one model.
HandleResult handle_request(codec::Bytes request, DataModel& model,
                            codec::MutableBytes out) noexcept;

// Resolves `unit_id` through `units` first: unknown units follow units.unknown_unit_policy;
// with units.broadcast_unit_zero, a unit-0 request runs on every model and gets NoResponse.
HandleResult handle_request(std::uint8_t unit_id, codec::Bytes request, const UnitModels& units,
                            codec::MutableBytes out) noexcept;

}  // namespace mbstorm::slave
