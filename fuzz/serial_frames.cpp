// libFuzzer harness: bytes from a serial line (or RTU/ASCII over TCP) through the frame reader,
// as a slave (requests) and as a master (responses), RTU and ASCII, cut into pieces with
// silences between them where the input's own bytes say so. Every frame handed out is bytes of
// the line, in order and not overlapping the previous frame, that decode as one frame of its
// framing (CRC or LRC right) with the same address and PDU; and the frames' bytes plus those
// dropped with an error never exceed what was fed.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "codec/ascii.hpp"
#include "codec/rtu.hpp"
#include "codec/serial_frame_reader.hpp"

namespace {

using namespace mbstorm::codec;

void check(bool ok) {
    if (!ok) std::abort();
}

// The frame decodes on its own as what the reader said it was.
void check_frame(const SerialFrame& f, Framing framing) {
    if (framing == Framing::Rtu) {
        RtuFrame d;
        check(decode_rtu_frame(f.adu, d) == CodecError::Ok);
        check(d.address == f.address &&
              std::equal(d.pdu.begin(), d.pdu.end(), f.pdu.begin(), f.pdu.end()));
        return;
    }
    std::vector<std::uint8_t> buf(f.adu.size());
    AsciiFrame d;
    check(decode_ascii_frame(f.adu, buf, d) == CodecError::Ok);
    check(d.address == f.address &&
          std::equal(d.pdu.begin(), d.pdu.end(), f.pdu.begin(), f.pdu.end()));
}

struct Tally {
    const std::uint8_t* line;
    std::size_t fed = 0, cursor = 0, accounted = 0;
};

void take(const SerialFrameReader::Result& r, const SerialFrame& f, Framing framing, Tally& t) {
    if (r.kind == SerialFrameReader::Result::Kind::Error) t.accounted += r.dropped;
    if (r.kind != SerialFrameReader::Result::Kind::Frame) return;
    check_frame(f, framing);
    const std::uint8_t* at =
        std::search(t.line + t.cursor, t.line + t.fed, f.adu.begin(), f.adu.end());
    check(at != t.line + t.fed);  // the line's own bytes, after the previous frame
    t.cursor = static_cast<std::size_t>(at - t.line) + f.adu.size();
    t.accounted += f.adu.size();
    check(t.accounted <= t.fed);
}

void read_all(const std::uint8_t* data, std::size_t size, Framing framing,
              SerialFrameReader::Reads reads) {
    SerialFrameReader reader(framing, reads);
    SerialFrame frame;
    Tally t{data};
    // Pieces of up to 16 bytes; a piece whose first byte is odd follows a silence.
    for (std::size_t at = 0; at < size;) {
        const std::size_t n = std::min<std::size_t>(size - at, 1 + data[at] % 16);
        reader.feed(Bytes(data + at, n), (data[at] & 1) != 0);
        at += n;
        t.fed = at;
        for (int i = 0; i < 512; ++i) {
            const auto r = reader.next(frame, (data[at - 1] & 2) != 0);
            take(r, frame, framing, t);
            if (r.kind == SerialFrameReader::Result::Kind::None) break;
        }
    }
    for (int i = 0; i < 512; ++i) {
        const auto r = reader.next(frame, true);
        take(r, frame, framing, t);
        if (r.kind == SerialFrameReader::Result::Kind::None) break;
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    for (const Framing framing : {Framing::Rtu, Framing::Ascii})
        for (const auto reads :
             {SerialFrameReader::Reads::Requests, SerialFrameReader::Reads::Responses})
            read_all(data, size, framing, reads);
    return 0;
}
