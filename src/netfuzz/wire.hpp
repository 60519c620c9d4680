// RTU and ASCII frames cut out of what the fuzzer sent or received, each with an MBAP view
// (the same unit and PDU behind a Modbus TCP header), so that one oracle judges every framing.
// MBAP streams are cut where they always were (executor.cpp, batch.cpp): this is for the
// framings without a length field or transaction id.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

#include "codec/bytes.hpp"
#include "codec/framing.hpp"

namespace mbstorm::netfuzz {

enum class WireCut : std::uint8_t {
    Frame,     // `out` holds the frame at the start of the bytes
    NeedMore,  // the frame is not complete yet
    Lost,      // no frame can start here (too long, or nothing a reader could end)
};

struct WireFrame {
    std::size_t size = 0;  // bytes of the stream it takes
    // Why a conforming reader discards it ("" when it does not): "bad-crc", "bad-lrc",
    // "bad-hex" or, for bytes before an ASCII ':', "noise".
    std::string_view discard;
    std::vector<std::uint8_t> mbap;  // MBAP view: tid, protocol id 0, length, unit, PDU
};

// Cuts the request (`request`) or response frame at the start of `bytes`. RTU: the length
// comes from the function code (the codec's inference) or, for a code without a length rule,
// from the first CRC that matches; ASCII: ':' up to LF. `tid` goes into the MBAP view.
WireCut cut_frame(codec::Bytes bytes, codec::Framing framing, bool request, std::uint16_t tid,
                  WireFrame& out);

// Whether `frame` (address, PDU, CRC) ends in the CRC of what comes before.
bool rtu_crc_ok(codec::Bytes frame) noexcept;

// The MBAP view of a unit and PDU.
std::vector<std::uint8_t> mbap_view(std::uint8_t unit, codec::Bytes pdu, std::uint16_t tid);

// An MBAP frame (header and PDU) as the same request in RTU or ASCII framing; MBAP unchanged.
std::vector<std::uint8_t> reframe(codec::Bytes mbap_frame, codec::Framing framing);

// Every whole request frame in `bytes` (any framing), as MBAP views; stops at the first that is
// not complete. `consumed` says how far it got.
std::vector<std::vector<std::uint8_t>> request_views(codec::Bytes bytes, codec::Framing framing,
                                                     std::size_t& consumed);

}  // namespace mbstorm::netfuzz
