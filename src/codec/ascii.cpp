// Modbus ASCII framing and the LRC.
#include "codec/ascii.hpp"

#include "codec/hex.hpp"

namespace mbstorm::codec {

namespace {
constexpr std::size_t kMinBinary = 3;  // address, function code, LRC
}  // namespace

std::uint8_t lrc(Bytes data) noexcept {
    std::uint8_t sum = 0;
    for (std::uint8_t b : data) sum = static_cast<std::uint8_t>(sum + b);
    return static_cast<std::uint8_t>(-sum);
}

CodecError decode_ascii_frame(Bytes text, MutableBytes buf, AsciiFrame& out) noexcept {
    out = AsciiFrame{};
    if (text.empty()) return CodecError::Empty;
    if (text[0] != ':') return CodecError::MissingStart;
    if (text.size() > limits::kMaxAsciiAdu) return CodecError::FrameTooLong;
    if (text.size() < 3 || text[text.size() - 2] != '\r' || text[text.size() - 1] != '\n') {
        return CodecError::MissingEnd;
    }
    const Bytes digits = text.subspan(1, text.size() - 3);
    if (digits.size() % 2 != 0) return CodecError::OddHexLength;
    for (std::uint8_t c : digits) {
        if (hex::digit_value(c) == hex::kNotHex) return CodecError::BadHexDigit;
    }
    const std::size_t n = digits.size() / 2;
    if (n < kMinBinary) return CodecError::Truncated;
    if (buf.size() < n) return CodecError::BufferTooSmall;
    for (std::size_t i = 0; i < n; ++i) {
        buf[i] = static_cast<std::uint8_t>((hex::digit_value(digits[2 * i]) << 4) |
                                           hex::digit_value(digits[2 * i + 1]));
    }
    // The LRC makes the sum of every decoded byte zero.
    if (lrc(Bytes(buf.data(), n)) != 0) return CodecError::BadLrc;
    out.address = buf[0];
    out.pdu = Bytes(buf.data() + 1, n - 2);
    out.binary = Bytes(buf.data(), n);
    return CodecError::Ok;
}

EncodeResult encode_ascii_frame(std::uint8_t address, Bytes pdu, MutableBytes out) noexcept {
    if (pdu.empty() || pdu.size() > limits::kMaxPdu) return {0, CodecError::InvalidArgument};
    const std::size_t total = ascii_frame_size(pdu.size());
    if (out.size() < total) return {0, CodecError::BufferTooSmall};
    std::uint8_t* p = out.data();
    auto put = [&p](std::uint8_t b) {
        *p++ = static_cast<std::uint8_t>(hex::kUpperDigits[b >> 4]);
        *p++ = static_cast<std::uint8_t>(hex::kUpperDigits[b & 0x0F]);
    };
    *p++ = ':';
    put(address);
    std::uint8_t sum = address;
    for (std::uint8_t b : pdu) {
        put(b);
        sum = static_cast<std::uint8_t>(sum + b);
    }
    put(static_cast<std::uint8_t>(-sum));
    *p++ = '\r';
    *p++ = '\n';
    return {total, CodecError::Ok};
}

}  // namespace mbstorm::codec
