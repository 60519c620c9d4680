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
#include "codec/function_code.hpp"
#include "codec/limits.hpp"
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

// FC08 event log bytes of a request handled normally.
inline constexpr std::uint8_t kReceiveEvent = 0x80;
inline constexpr std::uint8_t kSendEvent = 0x40;

namespace detail {
// The FC03/04 shortcut below; `by_words`: the register copy by whole words (read_be_words).
template <bool by_words>
[[gnu::always_inline]] inline bool answer_read(codec::Bytes request, DataModel& m,
                                               std::uint8_t* out, HandleResult& result) noexcept {
    if (request.size() != 5) return false;
    const std::uint8_t function = request[0];
    const bool holding =
        function == static_cast<std::uint8_t>(codec::FunctionCode::ReadHoldingRegisters);
    if (!holding && function != static_cast<std::uint8_t>(codec::FunctionCode::ReadInputRegisters))
        return false;
    const std::uint16_t address = codec::load_be16(request.data() + 1);
    const std::uint16_t quantity = codec::load_be16(request.data() + 3);
    RegisterTable& table = holding ? m.holding_registers() : m.input_registers();
    if (static_cast<std::uint16_t>(quantity - 1u) >= codec::limits::kMaxReadRegisters ||
        !table.contains(address, quantity))
        return false;
    if constexpr (by_words) {
        table.read_be_words(address, quantity, out + 2);  // may overwrite out[0], out[1]
    } else {
        table.read_be(address, quantity, out + 2);
    }
    out[0] = function;
    out[1] = static_cast<std::uint8_t>(2 * quantity);
    // One aggregate initialisation: built in a register, not field by field on the stack.
    result = HandleResult{2 + 2 * std::uint32_t{quantity}, Outcome::Response,
                          codec::ExceptionCode::None, function, false};
    return true;
}
}  // namespace detail

// FC03/FC04 that handle_request would answer normally (5 bytes, quantity 1..125, inside the
// table): the request of nearly every load test. Answers it with the same bytes and the same
// diagnostics as handle_request, without building a codec::Request; anything else (including
// every request owed an exception) returns false and must go to handle_request. Inline so a
// frame loop answers it without a call (the call's saved registers and the result passed
// back were 20-odd instructions of an FC03 x 10 transaction's ~300).
// Precondition: out holds at least kMinOutput bytes.
[[gnu::always_inline]] inline bool read_registers_inline(codec::Bytes request, DataModel& m,
                                                         std::uint8_t* out,
                                                         HandleResult& result) noexcept {
    if (!detail::answer_read<false>(request, m, out, result)) return false;
    if (m.track_diagnostics()) {
        Diagnostics& d = m.diagnostics();
        d.end_message(d.begin_message(), kReceiveEvent, kSendEvent);
    }
    return true;
}

// The server's version of read_registers_inline, cheaper by two things the caller takes on:
// - the diagnostics: the caller counts the reads answered here and hands them to
//   m.diagnostics().note_messages(count, kReceiveEvent, kSendEvent) (when
//   m.track_diagnostics()) before anything else handles a request for `m` and before the
//   answers go out (a locked increment per request was half of an FC03's handler time);
// - the copy by whole words (RegisterTable::read_be_words): kReadSlack bytes before `out`
//   and after its kMinOutput may be overwritten: [out - kReadSlack, out + kMinOutput +
//   kReadSlack) must be writable, and the caller writes whatever precedes `out` afterwards.
inline constexpr std::size_t kReadSlack = RegisterTable::kWordSlack;
[[gnu::always_inline]] inline bool read_registers_uncounted(codec::Bytes request, DataModel& m,
                                                            std::uint8_t* out,
                                                            HandleResult& result) noexcept {
    return detail::answer_read<true>(request, m, out, result);
}

// Resolves `unit_id` through `units` first: unknown units follow units.unknown_unit_policy;
// with units.broadcast_unit_zero, a unit-0 request runs on every model and gets NoResponse.
HandleResult handle_request(std::uint8_t unit_id, codec::Bytes request, const UnitModels& units,
                            codec::MutableBytes out) noexcept;

}  // namespace mbstorm::slave
