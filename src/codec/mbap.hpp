// Modbus TCP framing: the MBAP header and a stream splitter that turns arbitrary chunks of
// a byte stream into complete frames.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "codec/bytes.hpp"
#include "codec/error.hpp"
#include "codec/limits.hpp"
#include "codec/pdu.hpp"

namespace mbstorm::codec {

struct MbapHeader {
    std::uint16_t transaction_id = 0;
    std::uint16_t protocol_id = 0;
    std::uint16_t length = 0;  // bytes that follow: unit id + PDU
    std::uint8_t unit_id = 0;
};

// One complete TCP ADU: header plus views of the PDU and of the whole ADU.
struct TcpFrame {
    MbapHeader header;
    Bytes pdu;
    Bytes adu;
};

// Reads the 7-byte header (needs at least 7 bytes; no validation).
MbapHeader read_mbap_header(const std::uint8_t* p) noexcept;

// The whole ADU (header and PDU) a header announces: what a stream reader cuts, whether or
// not the length is valid.
constexpr std::size_t adu_size(const MbapHeader& h) noexcept {
    return limits::kMbapHeader - 1 + h.length;
}
// The same, from the first 6 bytes of a frame (needs at least 6 bytes).
inline std::size_t announced_adu_size(const std::uint8_t* frame) noexcept {
    return limits::kMbapHeader - 1 + load_be16(frame + 4);
}

// Validates a header: BadProtocolId, LengthZero, LengthOne, LengthTooLong or Ok.
CodecError check_mbap_header(const MbapHeader& h) noexcept;

// Decodes exactly one ADU (the whole of `adu`), LengthMismatch if sizes disagree.
CodecError decode_tcp_frame(Bytes adu, TcpFrame& out) noexcept;

// Writes the 7-byte header of an ADU carrying a `pdu_size`-byte PDU at `out` (7 bytes
// needed; not checked). For hot paths that build the PDU in place at out + 7.
inline void write_mbap_header(std::uint8_t* out, std::uint16_t transaction_id, std::uint8_t unit_id,
                              std::size_t pdu_size) noexcept {
    store_be16(out, transaction_id);
    store_be16(out + 2, 0);  // protocol id: Modbus
    store_be16(out + 4, static_cast<std::uint16_t>(pdu_size + 1));
    out[6] = unit_id;
}

// A whole exception ADU: header, function | 0x80, exception code.
inline constexpr std::size_t kExceptionAduSize = limits::kMbapHeader + 2;

// Writes the exception ADU answering `request` (its transaction and unit, its function with
// the exception bit; function 0 for a request without a PDU) at `out` (kExceptionAduSize
// bytes needed; not checked).
inline void write_exception_frame(std::uint8_t* out, const TcpFrame& request,
                                  ExceptionCode code) noexcept {
    write_mbap_header(out, request.header.transaction_id, request.header.unit_id, 2);
    const std::uint8_t function = request.pdu.empty() ? 0 : request.pdu[0];
    out[7] = static_cast<std::uint8_t>(function | kExceptionBit);
    out[8] = static_cast<std::uint8_t>(code);
}

// Writes header + PDU into `out`. The PDU may already sit at out[7..] (no copy then).
EncodeResult encode_tcp_frame(std::uint16_t transaction_id, std::uint8_t unit_id, Bytes pdu,
                              MutableBytes out) noexcept;

// The header fields a fuzzer may set to lie: any protocol id and length field, whatever the
// PDU (an empty or over-long one included).
struct RawMbapFields {
    std::uint16_t transaction_id = 0;
    std::uint16_t protocol_id = 0;
    std::uint16_t length = 0;  // written as given, not derived from the PDU
    std::uint8_t unit_id = 0;
};
// Writes a header with exactly `fields`, then `pdu` (any size that fits `out`). For fuzzers
// that must send frames which lie about their length through the codec.
EncodeResult encode_raw_tcp_frame(const RawMbapFields& fields, Bytes pdu,
                                  MutableBytes out) noexcept;

// Splits a TCP byte stream into frames. Feed it chunks as they arrive; call next() until it
// says NeedMore. Frames wholly inside the current chunk are returned as views into it
// (no copy); a frame split across chunks is assembled in a 260-byte internal buffer. Views
// stay valid until the next call to feed() or next().
//
// A header with protocol id != 0 is still a frame (its length is trustworthy enough to skip
// it): it is returned with status BadProtocolId so that servers can discard it and go on.
// Length 0, 1 or > 254 cannot be resynchronised: the splitter reports it and stays failed
// until reset().
class MbapSplitter {
  public:
    enum class Status : std::uint8_t {
        Frame,          // `out` holds a complete, valid frame
        NeedMore,       // the fed bytes are used up
        BadProtocolId,  // `out` holds a complete frame whose protocol id != 0 (discard it)
        Fatal,          // framing lost (see error()); call reset() before reuse
    };

    void feed(Bytes chunk) noexcept;
    // Inline for the common case (healthy, nothing buffered, a whole valid frame in the
    // chunk): it runs once per frame on the server's and the engine's hot paths, where the
    // call cost more than the work. Everything else is out of line in next_rest().
    Status next(TcpFrame& out) noexcept {
        const std::uint8_t* p = chunk_.data();
        const std::size_t avail = chunk_.size();
        if (avail >= limits::kMbapHeader && partial_size_ == 0 && error_ == CodecError::Ok)
            [[likely]] {
            const std::uint16_t length = load_be16(p + 4);
            const std::size_t total = length + 6u;
            if (length - 2u <= limits::kMaxMbapLength - 2u && load_be16(p + 2) == 0 &&
                avail >= total) [[likely]] {
                out.header.transaction_id = load_be16(p);
                out.header.protocol_id = 0;
                out.header.length = length;
                out.header.unit_id = p[6];
                out.pdu = Bytes(p + limits::kMbapHeader, length - 1u);
                out.adu = Bytes(p, total);
                chunk_ = Bytes(p + total, avail - total);
                return Status::Frame;
            }
        }
        return next_rest(out);
    }
    // The next frame whose protocol id is 0, counting the others in `skipped` and passing
    // them by: true with `out` set; false when the fed bytes are used up or the framing is
    // lost (failed()). What the receive loops of both workers' links want.
    bool next_modbus(TcpFrame& out, std::uint64_t& skipped) noexcept {
        for (;;) {
            switch (next(out)) {
                case Status::Frame:
                    return true;
                case Status::BadProtocolId:
                    ++skipped;
                    continue;
                case Status::NeedMore:
                case Status::Fatal:
                    return false;
            }
        }
    }
    bool failed() const noexcept { return error_ != CodecError::Ok; }
    CodecError error() const noexcept { return error_; }
    // Bytes of a partial frame held in the internal buffer.
    std::size_t buffered() const noexcept { return partial_size_; }
    // Bytes of the current chunk not yet consumed.
    std::size_t pending() const noexcept { return chunk_.size(); }
    void reset() noexcept;

  private:
    Status next_rest(TcpFrame& out) noexcept;

    Bytes chunk_;
    std::array<std::uint8_t, limits::kMaxTcpAdu> partial_{};
    std::size_t partial_size_ = 0;
    CodecError error_ = CodecError::Ok;
};

}  // namespace mbstorm::codec
