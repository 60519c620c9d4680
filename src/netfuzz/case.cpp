#include "netfuzz/case.hpp"

#include <algorithm>

#include "codec/ascii.hpp"
#include "codec/limits.hpp"
#include "codec/mbap.hpp"
#include "codec/rtu_stream.hpp"

#include <array>

namespace mbstorm::netfuzz {
namespace {

constexpr std::array<std::string_view, static_cast<std::size_t>(MutationClass::Count)> kNames = {
    "valid-limits",
    "invalid-values",
    "unknown-function",
    "unit-id",
    "transaction-id",
    "protocol-id",
    "mbap-length",
    "trailing-bytes",
    "truncated",
    "split",
    "coalesced",
    "drip",
    "half-close",
    "half-close-answered",
    "burst-split",
    "partial-hold",
    "exception-stall",
    "flood",
    "stateful-same",
    "stateful-cross",
    "recorded-mutation",
    "naive-random",
    "plaintext-to-tls",
    "plaintext-in-tls-session",
    "tls-to-plain",
    "bad-checksum",
    "broken-silence",
    "no-silence",
    "noise",
    "in-map",
    "map-edge",
    "coverage-mutation",
    "repeated-request"};

}  // namespace

std::string_view class_name(MutationClass c) noexcept {
    const auto i = static_cast<std::size_t>(c);
    return i < kNames.size() ? kNames[i] : "unknown";
}

bool class_from_name(std::string_view name, MutationClass& out) noexcept {
    for (std::size_t i = 0; i < kNames.size(); ++i) {
        if (kNames[i] == name) {
            out = static_cast<MutationClass>(i);
            return true;
        }
    }
    return false;
}

bool depends_on_line_timing(MutationClass c) noexcept {
    return c == MutationClass::BrokenSilence || c == MutationClass::Noise;
}

bool is_transport_class(MutationClass c) noexcept {
    switch (c) {
        case MutationClass::MbapLength:
        case MutationClass::Truncated:
        case MutationClass::Split:
        case MutationClass::Drip:
        case MutationClass::HalfClose:
        case MutationClass::BurstSplit:
        case MutationClass::PartialHold:
        case MutationClass::Flood:
        case MutationClass::BadChecksum:
        case MutationClass::BrokenSilence:
        case MutationClass::NoSilence:
        case MutationClass::Noise:
            return true;
        default:
            return false;
    }
}

std::string_view op_name(Op op) noexcept {
    switch (op) {
        case Op::Send:
            return "send";
        case Op::ShutdownWrite:
            return "shutdown-write";
        case Op::Await:
            return "await";
        case Op::Flood:
            return "flood";
        case Op::SideProbe:
            return "side-probe";
    }
    return "send";
}

bool op_from_name(std::string_view s, Op& out) noexcept {
    for (Op op : {Op::Send, Op::ShutdownWrite, Op::Await, Op::Flood, Op::SideProbe}) {
        if (op_name(op) == s) {
            out = op;
            return true;
        }
    }
    return false;
}

std::uint8_t Case::connections() const noexcept {
    std::uint8_t n = 0;
    for (const Step& s : steps)
        if (s.conn + 1 > n) n = static_cast<std::uint8_t>(s.conn + 1);
    return n;
}

std::vector<std::uint8_t> encode_pdu(const codec::Request& request) {
    std::array<std::uint8_t, codec::limits::kMaxPdu + 1> buffer;
    const codec::EncodeResult written =
        codec::encode_request(request, buffer, /*allow_invalid=*/true);
    return std::vector<std::uint8_t>(buffer.begin(),
                                     buffer.begin() + static_cast<std::ptrdiff_t>(written.size));
}

std::vector<std::uint8_t> register_bytes(const std::vector<std::uint16_t>& values) {
    std::vector<std::uint8_t> bytes(2 * values.size());
    for (std::size_t i = 0; i < values.size(); ++i)
        codec::store_be16(bytes.data() + 2 * i, values[i]);
    return bytes;
}

std::vector<std::uint8_t> frame_pdu(const std::vector<std::uint8_t>& pdu, std::uint16_t tid,
                                    std::uint8_t unit, codec::Framing framing) {
    if (framing == codec::Framing::Rtu) {
        std::vector<std::uint8_t> f(1 + pdu.size() + 2);
        f[0] = unit;
        std::copy(pdu.begin(), pdu.end(), f.begin() + 1);
        codec::append_rtu_crc(f.data(), 1 + pdu.size());
        return f;
    }
    if (framing == codec::Framing::Ascii) {
        std::vector<std::uint8_t> body;
        body.reserve(pdu.size() + 2);
        body.push_back(unit);
        for (std::uint8_t b : pdu) body.push_back(b);
        body.push_back(codec::lrc(codec::Bytes(body.data(), body.size())));
        static constexpr char kHex[] = "0123456789ABCDEF";
        std::vector<std::uint8_t> f(1, ':');
        for (std::uint8_t b : body) {
            f.push_back(static_cast<std::uint8_t>(kHex[b >> 4]));
            f.push_back(static_cast<std::uint8_t>(kHex[b & 0x0F]));
        }
        f.push_back('\r');
        f.push_back('\n');
        return f;
    }
    std::vector<std::uint8_t> f(codec::limits::kMbapHeader + pdu.size());
    codec::write_mbap_header(f.data(), tid, unit, pdu.size());
    std::copy(pdu.begin(), pdu.end(), f.begin() + codec::limits::kMbapHeader);
    return f;
}

}  // namespace mbstorm::netfuzz
