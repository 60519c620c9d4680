// Fuzzes Modbus ASCII decode/encode (exact-size buffers, so overruns are caught) and the
// CLI hex-text parser.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>
#include <vector>

#include "codec/ascii.hpp"
#include "codec/values.hpp"

using namespace mbstorm::codec;

namespace {

void check(bool ok) {
    if (!ok) std::abort();
}

char upper(std::uint8_t c) {
    return (c >= 'a' && c <= 'z') ? static_cast<char>(c - 'a' + 'A') : static_cast<char>(c);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::vector<std::uint8_t> text(data, data + size);

    // Decode into a buffer of exactly the size the frame can need.
    const std::size_t need = size >= 3 ? (size - 3) / 2 : 0;
    std::vector<std::uint8_t> buf(need);
    AsciiFrame f;
    const CodecError e = decode_ascii_frame(Bytes(text.data(), text.size()), buf, f);
    if (e == CodecError::Ok) {
        check(f.binary.size() == need && f.pdu.size() == need - 2);
        check(lrc(f.binary) == 0);
        // Re-encoding gives the input back, up to the case of the hex digits.
        std::vector<std::uint8_t> out(ascii_frame_size(f.pdu.size()));
        const EncodeResult r = encode_ascii_frame(f.address, f.pdu, out);
        check(r.ok() && r.size == size);
        for (std::size_t i = 0; i < size; ++i)
            check(out[i] == static_cast<std::uint8_t>(upper(text[i])));
        // One byte less of buffer must be refused, not overrun.
        if (need > 0) {
            std::vector<std::uint8_t> small(need - 1);
            AsciiFrame g;
            check(decode_ascii_frame(Bytes(text.data(), text.size()), small, g) ==
                  CodecError::BufferTooSmall);
        }
    }

    // The input as a PDU: encode, decode, compare.
    if (size >= 2) {
        const std::size_t pdu_size = std::min<std::size_t>(size - 1, limits::kMaxPdu);
        std::vector<std::uint8_t> out(ascii_frame_size(pdu_size));
        const EncodeResult r = encode_ascii_frame(data[0], Bytes(text.data() + 1, pdu_size), out);
        check(r.ok() && r.size == out.size());
        std::vector<std::uint8_t> bin(pdu_size + 2);
        AsciiFrame g;
        check(decode_ascii_frame(Bytes(out.data(), out.size()), bin, g) == CodecError::Ok);
        check(g.address == data[0] && std::equal(g.pdu.begin(), g.pdu.end(), data + 1));
    }

    // Hex text: exact-size output (at most one byte per two characters).
    const std::string_view sv(reinterpret_cast<const char*>(text.data()), text.size());
    std::vector<std::uint8_t> hex(size / 2);
    const HexParseResult h = parse_hex(sv, hex);
    check(h.size <= hex.size());
    if (h.ok()) {
        std::vector<std::uint8_t> again(h.size);
        const HexParseResult h2 = parse_hex(format_hex(Bytes(hex.data(), h.size)), again);
        check(h2.ok() && h2.size == h.size && std::equal(again.begin(), again.end(), hex.begin()));
    } else {
        check(h.position <= size);
    }
    return 0;
}
