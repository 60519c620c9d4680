// libFuzzer harness: bytes from a serial line (or RTU/ASCII over TCP) through the frame reader,
// as a slave (requests) and as a master (responses), RTU and ASCII, cut into pieces with
// silences between them where the input's own bytes say so.
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "codec/serial_frame_reader.hpp"

namespace {

using namespace mbstorm::codec;

void read_all(const std::uint8_t* data, std::size_t size, Framing framing,
              SerialFrameReader::Reads reads) {
    SerialFrameReader reader(framing, reads);
    SerialFrame frame;
    // Pieces of up to 16 bytes; a piece whose first byte is odd follows a silence.
    for (std::size_t at = 0; at < size;) {
        const std::size_t n = std::min<std::size_t>(size - at, 1 + data[at] % 16);
        reader.feed(Bytes(data + at, n), (data[at] & 1) != 0);
        at += n;
        for (int i = 0; i < 512; ++i) {
            const auto r = reader.next(frame, (data[at - 1] & 2) != 0);
            if (r.kind == SerialFrameReader::Result::Kind::None) break;
        }
    }
    for (int i = 0; i < 512; ++i)
        if (reader.next(frame, true).kind == SerialFrameReader::Result::Kind::None) break;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    for (const Framing framing : {Framing::Rtu, Framing::Ascii})
        for (const auto reads :
             {SerialFrameReader::Reads::Requests, SerialFrameReader::Reads::Responses})
            read_all(data, size, framing, reads);
    return 0;
}
