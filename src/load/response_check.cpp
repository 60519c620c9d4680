#include "load/response_check.hpp"

#include "codec/function_code.hpp"

namespace mbstorm::load {

using stats::Outcome;

stats::Outcome check_response(const RequestInfo& request, const codec::TcpFrame& frame,
                              codec::Response& rsp) noexcept {
    if (frame.header.unit_id != request.unit_id) return Outcome::WrongUnitId;
    if (frame.pdu.empty()) return Outcome::Malformed;
    if ((frame.pdu[0] & 0x7F) != request.function) return Outcome::WrongFunction;
    rsp = codec::Response{};
    if (codec::decode_response(frame.pdu, rsp) != codec::CodecError::Ok) return Outcome::Malformed;
    if (rsp.exception != codec::ExceptionCode::None) return Outcome::Exception;

    // decode_response() succeeded, so the function is public and has a descriptor.
    switch (codec::function_info(request.function)->response) {
        case codec::ResponseShape::Bits:
            if (rsp.payload.size() != (request.quantity + 7u) / 8u) return Outcome::Malformed;
            break;
        case codec::ResponseShape::Registers:
            if (rsp.payload.size() != 2u * request.quantity) return Outcome::Malformed;
            break;
        case codec::ResponseShape::EchoValue:
            if (rsp.address != request.address || rsp.value != request.value) {
                return Outcome::ValueMismatch;
            }
            break;
        case codec::ResponseShape::EchoQuantity:
            if (rsp.address != request.address || rsp.quantity != request.quantity) {
                return Outcome::ValueMismatch;
            }
            break;
        case codec::ResponseShape::EchoMask:
            if (rsp.address != request.address || rsp.and_mask != request.and_mask ||
                rsp.or_mask != request.value) {
                return Outcome::ValueMismatch;
            }
            break;
        case codec::ResponseShape::EchoSubFunction:
            if (rsp.sub_function != request.sub_function) return Outcome::ValueMismatch;
            break;
        case codec::ResponseShape::ExceptionStatus:
        case codec::ResponseShape::EventCounter:
        case codec::ResponseShape::EventLog:
        case codec::ResponseShape::ServerId:
        case codec::ResponseShape::FileRecords:
        case codec::ResponseShape::FifoValues:
        case codec::ResponseShape::MeiObjects:
            break;  // nothing the request predicts
    }
    return Outcome::Ok;
}

}  // namespace mbstorm::load
