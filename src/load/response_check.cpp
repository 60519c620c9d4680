#include "load/response_check.hpp"

#include "codec/function_code.hpp"
#include "codec/limits.hpp"

namespace mbstorm::load {

using stats::Outcome;

namespace {

// An answer of `bytes` data bytes to this read, byte count and function code as asked.
bool read_data_fits(const RequestInfo& request, codec::Bytes pdu, std::size_t bytes) noexcept {
    return bytes != 0 && bytes <= 2u * codec::limits::kMaxReadRegisters &&
           pdu.size() == 2 + bytes && pdu[0] == request.function && pdu[1] == bytes;
}

// A FC01-04 answer with exactly the data the request asked for: what decode_response() and
// the size check below would accept, decided without them (the answer to nearly every
// request of a load test). Anything else, exceptions included, takes the full check.
bool read_data_as_expected(const RequestInfo& request, codec::Bytes pdu) noexcept {
    using FC = codec::FunctionCode;
    switch (static_cast<FC>(request.function)) {
        case FC::ReadCoils:
        case FC::ReadDiscreteInputs:
            return read_data_fits(request, pdu, (request.quantity + 7u) / 8u);
        case FC::ReadHoldingRegisters:
        case FC::ReadInputRegisters:
            return read_data_fits(request, pdu, 2u * request.quantity);
        case FC::WriteSingleCoil:
        case FC::WriteSingleRegister:
        case FC::ReadExceptionStatus:
        case FC::Diagnostics:
        case FC::GetCommEventCounter:
        case FC::GetCommEventLog:
        case FC::WriteMultipleCoils:
        case FC::WriteMultipleRegisters:
        case FC::ReportServerId:
        case FC::ReadFileRecord:
        case FC::WriteFileRecord:
        case FC::MaskWriteRegister:
        case FC::ReadWriteMultipleRegisters:
        case FC::ReadFifoQueue:
        case FC::EncapsulatedInterface:
            return false;
    }
    return false;  // not a public code
}

}  // namespace

stats::Outcome check_response(const RequestInfo& request, const codec::TcpFrame& frame,
                              codec::Response& rsp) noexcept {
    if (frame.header.unit_id != request.unit_id) return Outcome::WrongUnitId;
    if (frame.pdu.empty()) return Outcome::Malformed;
    if ((frame.pdu[0] & 0x7F) != request.function) return Outcome::WrongFunction;
    rsp = codec::Response{};
    if (read_data_as_expected(request, frame.pdu)) {
        rsp.function = request.function;
        rsp.payload = frame.pdu.subspan(2);
        return Outcome::Ok;
    }
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
