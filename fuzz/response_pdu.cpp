// libFuzzer: arbitrary bytes as a response PDU. Decode, walk every variable part, and
// re-encode whatever was accepted: it must reproduce the input.
#include <cstdint>
#include <cstdlib>
#include <cstring>

#include "codec/pdu.hpp"

using namespace mbstorm::codec;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    Response rsp;
    if (decode_response(Bytes(data, size), rsp) != CodecError::Ok) return 0;

    if (rsp.exception == ExceptionCode::None) {
        if (rsp.function == 0x2B) {
            DeviceIdObjectIterator it(rsp.payload);
            DeviceIdObject o;
            unsigned n = 0;
            while (it.next(o) == CodecError::Ok) ++n;
            if (n != rsp.object_count) std::abort();
        } else if (rsp.function == 0x14) {
            FileResponseIterator it(rsp.payload);
            FileSubResponse s;
            while (it.next(s) == CodecError::Ok) {
            }
        } else if (rsp.function == 0x15) {
            FileRecordIterator it(rsp.payload, true);
            FileSubRequest s;
            while (it.next(s) == CodecError::Ok) {
            }
        }
    }

    std::uint8_t out[260];
    const EncodeResult enc = encode_response(rsp, MutableBytes(out, sizeof out));
    if (!enc.ok() || enc.size != size || std::memcmp(out, data, size) != 0) std::abort();
    return 0;
}
