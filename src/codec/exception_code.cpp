// Spec names of the exception codes.
#include "codec/exception_code.hpp"

namespace mbstorm::codec {

std::string_view exception_name(ExceptionCode code) noexcept {
    switch (code) {
        case ExceptionCode::IllegalFunction:
            return "ILLEGAL FUNCTION";
        case ExceptionCode::IllegalDataAddress:
            return "ILLEGAL DATA ADDRESS";
        case ExceptionCode::IllegalDataValue:
            return "ILLEGAL DATA VALUE";
        case ExceptionCode::ServerDeviceFailure:
            return "SERVER DEVICE FAILURE";
        case ExceptionCode::Acknowledge:
            return "ACKNOWLEDGE";
        case ExceptionCode::ServerDeviceBusy:
            return "SERVER DEVICE BUSY";
        case ExceptionCode::MemoryParityError:
            return "MEMORY PARITY ERROR";
        case ExceptionCode::GatewayPathUnavailable:
            return "GATEWAY PATH UNAVAILABLE";
        case ExceptionCode::GatewayTargetFailedToRespond:
            return "GATEWAY TARGET DEVICE FAILED TO RESPOND";
        case ExceptionCode::None:
            break;
    }
    return "UNKNOWN EXCEPTION";
}

bool is_known_exception(std::uint8_t code) noexcept {
    switch (code) {
        case 0x01:
        case 0x02:
        case 0x03:
        case 0x04:
        case 0x05:
        case 0x06:
        case 0x08:
        case 0x0A:
        case 0x0B:
            return true;
        default:
            return false;
    }
}

}  // namespace mbstorm::codec
