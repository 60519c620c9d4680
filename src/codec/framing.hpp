// How Modbus PDUs are framed on a byte stream: MBAP (Modbus TCP, TLS), RTU (unit, PDU,
// CRC-16: serial lines and RTU over TCP) or ASCII (':' hex LRC CR LF: serial lines).
#pragma once

#include <cstdint>
#include <string_view>

namespace mbstorm::codec {

enum class Framing : std::uint8_t { Mbap, Rtu, Ascii };

constexpr std::string_view framing_name(Framing f) noexcept {
    switch (f) {
        case Framing::Mbap:
            return "mbap";
        case Framing::Rtu:
            return "rtu";
        case Framing::Ascii:
            return "ascii";
    }
    return "?";
}

}  // namespace mbstorm::codec
