// libFuzzer: arbitrary bytes as a response PDU. Decode, walk every variable part, and
// re-encode whatever was accepted: it must reproduce the input.
#include <cstdint>
#include <cstdlib>
#include <cstring>

#include "codec/function_code.hpp"
#include "codec/pdu.hpp"
#include "codec/pdu_layout.hpp"

using namespace mbstorm::codec;

namespace {

// Walks a field with a variable part of its own, as decode does (the codec's layout says
// which): iterators must stop inside the payload, and the objects must be as many as counted.
void walk(const PduField& field, const Response& rsp) {
    switch (field.kind) {
        case FieldKind::DeviceIdObjects: {
            DeviceIdObjectIterator it(rsp.payload);
            DeviceIdObject o;
            unsigned n = 0;
            while (it.next(o) == CodecError::Ok) ++n;
            if (n != rsp.object_count) std::abort();
            break;
        }
        case FieldKind::FileSubResponses: {
            FileResponseIterator it(rsp.payload);
            FileSubResponse s;
            while (it.next(s) == CodecError::Ok) {
            }
            break;
        }
        case FieldKind::FileSubRequests:
        case FieldKind::FileSubRequestsWithData: {
            FileRecordIterator it(rsp.payload, field.kind == FieldKind::FileSubRequestsWithData);
            FileSubRequest s;
            while (it.next(s) == CodecError::Ok) {
            }
            break;
        }
        case FieldKind::Byte:
        case FieldKind::Word:
        case FieldKind::CoilValue:
        case FieldKind::MeiType:
        case FieldKind::MoreFollows:
        case FieldKind::Registers:
        case FieldKind::PackedBits:
        case FieldKind::Rest:
            break;  // read in place: nothing to iterate
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    Response rsp;
    if (decode_response(Bytes(data, size), rsp) != CodecError::Ok) return 0;

    if (rsp.exception == ExceptionCode::None) {
        // decode_response() accepted it, so the function is public and has a descriptor.
        for (const PduField& field : response_layout(*function_info(rsp.function)).fields)
            walk(field, rsp);
    }

    std::uint8_t out[260];
    const EncodeResult enc = encode_response(rsp, MutableBytes(out, sizeof out));
    if (!enc.ok() || enc.size != size || std::memcmp(out, data, size) != 0) std::abort();
    return 0;
}
