// libFuzzer: arbitrary bytes as a request PDU. The decoder must never read past the input,
// must owe an exception exactly when it rejects a PDU that has a function code, and whatever
// it accepts must re-encode to the same bytes.
#include <cstdint>
#include <cstdlib>
#include <cstring>

#include "codec/pdu.hpp"

using namespace mbstorm::codec;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    Request req;
    const RequestStatus st = decode_request(Bytes(data, size), req);
    if (st.ok() != (st.exception == ExceptionCode::None)) {
        if (st.error != CodecError::Empty) std::abort();
    }
    if (!st.ok()) return 0;

    FileRecordIterator files(req.payload, req.function == 0x15);
    FileSubRequest sub;
    while (files.next(sub) == CodecError::Ok) {
    }

    std::uint8_t out[260];
    const EncodeResult enc = encode_request(req, MutableBytes(out, sizeof out));
    if (!enc.ok() || enc.size != size || std::memcmp(out, data, size) != 0) std::abort();
    (void)expected_read_byte_count(req);
    return 0;
}
