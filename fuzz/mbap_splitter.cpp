// Fuzzes MbapSplitter: the input chooses its own chunking (a few leading control bytes give
// the chunk sizes), and the frames that come out must equal a plain whole-buffer parse.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "codec/mbap.hpp"

using namespace mbstorm::codec;

namespace {

void check(bool ok) {
    if (!ok) std::abort();
}

struct RefFrame {
    std::size_t offset;
    std::size_t size;
    bool bad_protocol;
};

// Reference: walk the whole stream at once.
struct RefResult {
    std::vector<RefFrame> frames;
    CodecError fatal = CodecError::Ok;
    std::size_t tail = 0;  // bytes after the last frame (when not fatal)
};

RefResult reference_split(const std::uint8_t* s, std::size_t n) {
    RefResult r;
    std::size_t off = 0;
    while (n - off >= limits::kMbapHeader) {
        const MbapHeader h = read_mbap_header(s + off);
        if (h.length == 0)
            r.fatal = CodecError::LengthZero;
        else if (h.length == 1)
            r.fatal = CodecError::LengthOne;
        else if (h.length > 254)
            r.fatal = CodecError::LengthTooLong;
        if (r.fatal != CodecError::Ok) return r;
        const std::size_t total = h.length + 6u;
        if (n - off < total) break;
        r.frames.push_back({off, total, h.protocol_id != 0});
        off += total;
    }
    r.tail = n - off;
    return r;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size < 1) return 0;
    const std::size_t controls = (data[0] & 0x0F) + 1;
    if (size < 1 + controls) return 0;
    const std::uint8_t* control = data + 1;
    // Own copy so that ASan catches any read past the stream.
    const std::vector<std::uint8_t> stream(data + 1 + controls, data + size);
    const RefResult ref = reference_split(stream.data(), stream.size());

    MbapSplitter sp;
    std::size_t off = 0;
    std::size_t got = 0;
    bool fatal = false;
    std::size_t round = 0;
    while (off < stream.size() && !fatal) {
        std::size_t chunk = control[round % controls];
        // All-zero control bytes would never progress: finish with one chunk.
        if (round > 2 * stream.size() + 64) chunk = stream.size() - off;
        ++round;
        if (chunk > stream.size() - off) chunk = stream.size() - off;
        // Heap copy of exactly the chunk: reading outside it is caught.
        std::vector<std::uint8_t> piece(stream.begin() + static_cast<std::ptrdiff_t>(off),
                                        stream.begin() + static_cast<std::ptrdiff_t>(off + chunk));
        sp.feed(Bytes(piece.data(), piece.size()));
        off += chunk;
        while (true) {
            TcpFrame f;
            const MbapSplitter::Status st = sp.next(f);
            if (st == MbapSplitter::Status::NeedMore) {
                check(sp.pending() == 0);
                break;
            }
            if (st == MbapSplitter::Status::Fatal) {
                check(ref.fatal != CodecError::Ok && sp.error() == ref.fatal);
                check(got == ref.frames.size());
                fatal = true;
                break;
            }
            // Every frame: a valid header whose length matches the PDU.
            check(got < ref.frames.size());
            const RefFrame& want = ref.frames[got++];
            check(f.adu.size() == want.size);
            check(f.header.length >= 2 && f.header.length <= limits::kMaxMbapLength);
            check(f.adu.size() == f.header.length + 6u);
            check(f.pdu.size() == f.header.length - 1u);
            check(f.pdu.data() == f.adu.data() + limits::kMbapHeader);
            check((st == MbapSplitter::Status::BadProtocolId) == want.bad_protocol);
            check((f.header.protocol_id != 0) == want.bad_protocol);
            for (std::size_t i = 0; i < f.adu.size(); ++i) {
                check(f.adu[i] == stream[want.offset + i]);
            }
            TcpFrame again;
            const CodecError e = decode_tcp_frame(f.adu, again);
            check(e == (want.bad_protocol ? CodecError::BadProtocolId : CodecError::Ok));
        }
    }
    // The whole stream was fed, so a bad header the reference saw must have been reported.
    check(fatal == (ref.fatal != CodecError::Ok));
    if (!fatal) {
        check(got == ref.frames.size());
        check(sp.buffered() == ref.tail);
    }
    return 0;
}
