#include "load/response_check.hpp"

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

    switch (request.function) {
        case 0x01:
        case 0x02:
            if (rsp.payload.size() != (request.quantity + 7u) / 8u) return Outcome::Malformed;
            break;
        case 0x03:
        case 0x04:
        case 0x17:
            if (rsp.payload.size() != 2u * request.quantity) return Outcome::Malformed;
            break;
        case 0x05:
        case 0x06:
            if (rsp.address != request.address || rsp.value != request.value) {
                return Outcome::ValueMismatch;
            }
            break;
        case 0x0F:
        case 0x10:
            if (rsp.address != request.address || rsp.quantity != request.quantity) {
                return Outcome::ValueMismatch;
            }
            break;
        case 0x16:
            if (rsp.address != request.address || rsp.and_mask != request.and_mask ||
                rsp.or_mask != request.value) {
                return Outcome::ValueMismatch;
            }
            break;
        case 0x08:
            if (rsp.sub_function != request.sub_function) return Outcome::ValueMismatch;
            break;
        default:
            break;
    }
    return Outcome::Ok;
}

}  // namespace mbstorm::load
