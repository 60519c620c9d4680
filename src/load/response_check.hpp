// Checks one response frame against the request it answers: unit id, function code, decoding,
// exception, and the echo / byte count the request implies. Pure; no allocation.
#pragma once

#include "codec/mbap.hpp"
#include "codec/pdu.hpp"
#include "load/request_info.hpp"
#include "stats/counters.hpp"

namespace mbstorm::load {

// Outcome::Ok, Exception (code in rsp.exception), WrongUnitId, WrongFunction, Malformed (does
// not decode or its size disagrees with the request), or ValueMismatch (an echo differs).
stats::Outcome check_response(const RequestInfo& request, const codec::TcpFrame& frame,
                              codec::Response& rsp) noexcept;

// The answer to nearly every request of a load test, an FC01-04 answer with exactly the data
// asked for, told in a few compares against what the request expects: check_response() says Ok
// to every frame this accepts (its payload is frame.pdu.subspan(2)). False says nothing: the
// frame then takes check_response().
inline bool is_expected_read_answer(const RequestInfo& request,
                                    const codec::TcpFrame& frame) noexcept {
    return request.answer_bytes != 0 && frame.pdu.size() == 2u + request.answer_bytes &&
           frame.header.unit_id == request.unit_id && frame.pdu[0] == request.function &&
           frame.pdu[1] == request.answer_bytes;
}

}  // namespace mbstorm::load
