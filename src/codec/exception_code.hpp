// Modbus exception codes (the byte after function|0x80).
#pragma once

#include <cstdint>
#include <string_view>

namespace mbstorm::codec {

enum class ExceptionCode : std::uint8_t {
    None = 0x00,  // not an exception: the request is fine as far as the codec can tell
    IllegalFunction = 0x01,
    IllegalDataAddress = 0x02,
    IllegalDataValue = 0x03,
    ServerDeviceFailure = 0x04,
    Acknowledge = 0x05,
    ServerDeviceBusy = 0x06,
    MemoryParityError = 0x08,
    GatewayPathUnavailable = 0x0A,
    GatewayTargetFailedToRespond = 0x0B,
};

// Spec name, e.g. "ILLEGAL DATA ADDRESS"; "UNKNOWN EXCEPTION" for other values.
std::string_view exception_name(ExceptionCode code) noexcept;
// True for the nine codes the specification defines.
bool is_known_exception(std::uint8_t code) noexcept;

}  // namespace mbstorm::codec
