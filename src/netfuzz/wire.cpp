#include "netfuzz/wire.hpp"

#include <algorithm>

#include "codec/ascii.hpp"
#include "codec/limits.hpp"
#include "codec/mbap.hpp"
#include "codec/rtu.hpp"
#include "netfuzz/case.hpp"

namespace mbstorm::netfuzz {
namespace {

namespace lim = codec::limits;

bool crc_matches(const std::uint8_t* p, std::size_t size) noexcept {
    if (size < codec::kMinRtuAdu) return false;
    const std::uint16_t crc = codec::crc16(codec::Bytes(p, size - 2));
    return p[size - 2] == (crc & 0xFF) && p[size - 1] == (crc >> 8);
}

int hex_value(std::uint8_t c) noexcept {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    return -1;
}

WireCut cut_rtu(codec::Bytes bytes, bool request, std::uint16_t tid, WireFrame& out) {
    std::size_t size = 0;
    for (int guard = 0; guard < 8 && size == 0; ++guard) {
        const codec::RtuLength len =
            request ? codec::rtu_request_length(bytes) : codec::rtu_response_length(bytes);
        switch (len.status) {
            case codec::RtuLength::Status::Known:
                if (bytes.size() < len.size) return WireCut::NeedMore;
                size = len.size;
                break;
            case codec::RtuLength::Status::NeedMore:
                if (bytes.size() < len.size || len.size == 0) return WireCut::NeedMore;
                break;  // enough for the next question
            case codec::RtuLength::Status::TooLong:
                return WireCut::Lost;
            case codec::RtuLength::Status::Unknown: {
                // No length rule: the frame ends at the first byte after which the bytes so far
                // end in their CRC (as the server's splitter reads such a frame).
                const std::size_t most = std::min(bytes.size(), lim::kMaxRtuAdu);
                for (std::size_t n = codec::kMinRtuAdu; n <= most && !size; ++n)
                    if (crc_matches(bytes.data(), n)) size = n;
                if (!size)
                    return bytes.size() >= lim::kMaxRtuAdu ? WireCut::Lost : WireCut::NeedMore;
                break;
            }
        }
    }
    if (size == 0) return WireCut::NeedMore;
    out.size = size;
    out.discard = crc_matches(bytes.data(), size) ? std::string_view() : "bad-crc";
    out.mbap = mbap_view(bytes[0], bytes.subspan(1, size - 3), tid);
    return WireCut::Frame;
}

WireCut cut_ascii(codec::Bytes bytes, std::uint16_t tid, WireFrame& out) {
    if (bytes.empty()) return WireCut::NeedMore;
    if (bytes[0] != ':') {
        // Bytes before a ':' are noise a reader skips while it looks for the next frame.
        const auto colon = std::find(bytes.begin(), bytes.end(), std::uint8_t{':'});
        if (colon == bytes.end()) return WireCut::NeedMore;
        out.size = static_cast<std::size_t>(colon - bytes.begin());
        out.discard = "noise";
        out.mbap = mbap_view(0, {}, tid);
        return WireCut::Frame;
    }
    const auto lf = std::find(bytes.begin(), bytes.end(), std::uint8_t{'\n'});
    if (lf == bytes.end())
        return bytes.size() > 2 * lim::kMaxRtuAdu + 3 ? WireCut::Lost : WireCut::NeedMore;
    out.size = static_cast<std::size_t>(lf - bytes.begin()) + 1;
    const codec::Bytes text = bytes.first(out.size);
    // The view: as many whole hex pairs as there are between ':' and CR LF.
    std::vector<std::uint8_t> bin;
    for (std::size_t i = 1; i + 1 < out.size - 1; i += 2) {
        const int hi = hex_value(text[i]), lo = hex_value(text[i + 1]);
        if (hi < 0 || lo < 0) break;
        bin.push_back(static_cast<std::uint8_t>(hi << 4 | lo));
    }
    std::vector<std::uint8_t> buf(out.size / 2 + 1);
    codec::AsciiFrame frame;
    const codec::CodecError err = codec::decode_ascii_frame(text, buf, frame);
    out.discard = err == codec::CodecError::Ok       ? std::string_view()
                  : err == codec::CodecError::BadLrc ? "bad-lrc"
                                                     : "bad-hex";
    const std::uint8_t unit = bin.empty() ? 0 : bin[0];
    const std::size_t pdu_size = bin.size() >= 2 ? bin.size() - 2 : 0;  // no unit, no LRC
    out.mbap = mbap_view(
        unit, codec::Bytes(bin.data() + std::min<std::size_t>(1, bin.size()), pdu_size), tid);
    return WireCut::Frame;
}

}  // namespace

bool rtu_crc_ok(codec::Bytes frame) noexcept {
    return crc_matches(frame.data(), frame.size());
}

std::vector<std::uint8_t> mbap_view(std::uint8_t unit, codec::Bytes pdu, std::uint16_t tid) {
    std::vector<std::uint8_t> v(lim::kMbapHeader + pdu.size());
    codec::write_mbap_header(v.data(), tid, unit, pdu.size());
    std::copy(pdu.begin(), pdu.end(), v.begin() + lim::kMbapHeader);
    return v;
}

WireCut cut_frame(codec::Bytes bytes, codec::Framing framing, bool request, std::uint16_t tid,
                  WireFrame& out) {
    out = WireFrame{};
    switch (framing) {
        case codec::Framing::Rtu:
            return cut_rtu(bytes, request, tid, out);
        case codec::Framing::Ascii:
            return cut_ascii(bytes, tid, out);
        case codec::Framing::Mbap:
            break;
    }
    if (bytes.size() < lim::kMbapHeader) return WireCut::NeedMore;
    const std::size_t size = codec::announced_adu_size(bytes.data());
    if (size <= lim::kMbapHeader) return WireCut::Lost;
    if (bytes.size() < size) return WireCut::NeedMore;
    out.size = size;
    out.mbap.assign(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(size));
    return WireCut::Frame;
}

std::vector<std::uint8_t> reframe(codec::Bytes mbap_frame, codec::Framing framing) {
    if (framing == codec::Framing::Mbap || mbap_frame.size() < lim::kMbapHeader)
        return {mbap_frame.begin(), mbap_frame.end()};
    const codec::Bytes pdu = mbap_frame.subspan(lim::kMbapHeader);
    return frame_pdu({pdu.begin(), pdu.end()}, 0, mbap_frame[lim::kMbapHeader - 1], framing);
}

std::vector<std::vector<std::uint8_t>> request_views(codec::Bytes bytes, codec::Framing framing,
                                                     std::size_t& consumed) {
    std::vector<std::vector<std::uint8_t>> out;
    consumed = 0;
    while (consumed < bytes.size()) {
        WireFrame f;
        if (cut_frame(bytes.subspan(consumed), framing, true, 0, f) != WireCut::Frame) break;
        consumed += f.size;
        if (f.discard != "noise") out.push_back(std::move(f.mbap));
    }
    return out;
}

}  // namespace mbstorm::netfuzz
