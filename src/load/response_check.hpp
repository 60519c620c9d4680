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

}  // namespace mbstorm::load
