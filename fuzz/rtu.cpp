// Fuzzes RTU framing: length inference must be consistent across prefixes, never read past
// the bytes given, and agree with frame decode; encode/decode must round-trip.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "codec/rtu.hpp"

using namespace mbstorm::codec;

namespace {

void check(bool ok) {
    if (!ok) std::abort();
}

bool same(const RtuLength& a, const RtuLength& b) {
    return a.status == b.status && a.size == b.size;
}

void check_inference(RtuLength (*infer)(Bytes), const std::vector<std::uint8_t>& data) {
    const std::size_t n = std::min<std::size_t>(data.size(), 300);
    std::vector<RtuLength> at(n + 1);
    for (std::size_t k = 0; k <= n; ++k) {
        // Exact-size heap copy: any read past the prefix is an ASan report.
        const std::vector<std::uint8_t> prefix(data.begin(),
                                               data.begin() + static_cast<std::ptrdiff_t>(k));
        at[k] = infer(Bytes(prefix.data(), prefix.size()));
        const RtuLength& r = at[k];
        switch (r.status) {
            case RtuLength::Status::Known:
                check(r.size >= 4 && r.size <= limits::kMaxRtuAdu);
                break;
            case RtuLength::Status::NeedMore:
                check(r.size > k && r.size <= limits::kMaxRtuAdu);
                break;
            case RtuLength::Status::TooLong:
                check(r.size > limits::kMaxRtuAdu);
                break;
            case RtuLength::Status::Unknown:
                break;
        }
    }
    for (std::size_t k = 0; k <= n; ++k) {
        if (at[k].status == RtuLength::Status::NeedMore) {
            // Nothing changes until the requested bytes are there.
            for (std::size_t j = k; j < std::min(at[k].size, n + 1); ++j) check(same(at[j], at[k]));
        } else {
            // A final answer stays final.
            for (std::size_t j = k; j <= n; ++j) check(same(at[j], at[k]));
        }
    }
    const RtuLength& last = at[n];
    if (last.status == RtuLength::Status::Known && last.size <= data.size()) {
        const std::vector<std::uint8_t> frame(
            data.begin(), data.begin() + static_cast<std::ptrdiff_t>(last.size));
        RtuFrame f;
        const CodecError e = decode_rtu_frame(Bytes(frame.data(), frame.size()), f);
        check(e == CodecError::Ok || e == CodecError::BadCrc);
        if (e == CodecError::Ok) {
            check(f.pdu.size() == last.size - 3);
            check(infer(f.adu).size == last.size);
        }
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::vector<std::uint8_t> input(data, data + size);
    check_inference(rtu_request_length, input);
    check_inference(rtu_response_length, input);

    // Decode the whole input as one frame.
    RtuFrame f;
    const CodecError e = decode_rtu_frame(Bytes(input.data(), input.size()), f);
    if (e == CodecError::Ok) {
        check(f.adu.size() == size && f.pdu.size() == size - 3 && f.address == data[0]);
        check(crc16(f.adu) == 0);  // a correct frame leaves no CRC residue
    }

    // Encode address + PDU taken from the input into an exact-size buffer and back.
    if (size >= 2) {
        const std::size_t pdu_size = std::min<std::size_t>(size - 1, limits::kMaxPdu);
        std::vector<std::uint8_t> out(pdu_size + 3);
        const EncodeResult r = encode_rtu_frame(data[0], Bytes(input.data() + 1, pdu_size), out);
        check(r.ok() && r.size == out.size());
        RtuFrame back;
        check(decode_rtu_frame(Bytes(out.data(), r.size), back) == CodecError::Ok);
        check(back.address == data[0] && std::equal(back.pdu.begin(), back.pdu.end(), data + 1));
    }
    return 0;
}
