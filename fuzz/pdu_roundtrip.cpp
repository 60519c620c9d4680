// libFuzzer: both directions of the round-trip property.
//  1. bytes -> decode -> encode must give the same bytes (requests and responses).
//  2. fields -> validated encode -> decode -> encode must give the same bytes, and the
//     decoded fields must equal the ones encoded; unvalidated encodes never overrun.
#include <cstdint>
#include <cstdlib>
#include <cstring>

#include "codec/pdu.hpp"

using namespace mbstorm::codec;

namespace {

// Reads fields from the fuzz input, zero once it runs out.
struct Cursor {
    const std::uint8_t* p;
    std::size_t n;
    std::uint8_t u8() {
        if (n == 0) return 0;
        --n;
        return *p++;
    }
    std::uint16_t u16() {
        const std::uint16_t hi = u8();
        return static_cast<std::uint16_t>((hi << 8) | u8());
    }
    Bytes rest() { return Bytes(p, n); }
};

void bytes_round_trip(const std::uint8_t* data, std::size_t size) {
    std::uint8_t out[260];
    Request req;
    if (decode_request(Bytes(data, size), req).ok()) {
        const EncodeResult e = encode_request(req, MutableBytes(out, sizeof out));
        if (!e.ok() || e.size != size || std::memcmp(out, data, size) != 0) std::abort();
    }
    Response rsp;
    if (decode_response(Bytes(data, size), rsp) == CodecError::Ok) {
        const EncodeResult e = encode_response(rsp, MutableBytes(out, sizeof out));
        if (!e.ok() || e.size != size || std::memcmp(out, data, size) != 0) std::abort();
    }
}

void fields_round_trip(Cursor c) {
    Request r;
    r.function = c.u8();
    r.address = c.u16();
    r.quantity = c.u16();
    r.value = c.u16();
    r.and_mask = c.u16();
    r.or_mask = c.u16();
    r.write_address = c.u16();
    r.write_quantity = c.u16();
    r.sub_function = c.u16();
    r.mei_type = c.u8();
    r.device_id_code = c.u8();
    r.object_id = c.u8();
    r.payload = c.rest();

    // Unvalidated encodes land inside the buffer whatever the fields say.
    std::uint8_t small[16];
    const EncodeResult raw = encode_request(r, MutableBytes(small, sizeof small), true);
    if (raw.ok() && raw.size > sizeof small) std::abort();

    std::uint8_t out[300];
    const EncodeResult enc = encode_request(r, MutableBytes(out, sizeof out));
    if (!enc.ok()) return;
    Request back;
    if (!decode_request(Bytes(out, enc.size), back).ok()) std::abort();
    if (back.function != r.function) std::abort();
    std::uint8_t again[300];
    const EncodeResult enc2 = encode_request(back, MutableBytes(again, sizeof again));
    if (!enc2.ok() || enc2.size != enc.size || std::memcmp(out, again, enc.size) != 0) {
        std::abort();
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    bytes_round_trip(data, size);
    fields_round_trip(Cursor{data, size});
    return 0;
}
