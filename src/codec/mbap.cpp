// MBAP header helpers and the TCP stream splitter (the server's hot path: no allocation,
// frames inside the current chunk are returned as views).
#include "codec/mbap.hpp"

#include <algorithm>
#include <cstring>

namespace mbstorm::codec {

namespace {

// Length errors come first: they make the stream impossible to resynchronise, whereas a
// bad protocol id still leaves a usable length.
constexpr CodecError check_fields(std::uint16_t protocol_id, std::uint16_t length) noexcept {
    if (length < 2) return length == 0 ? CodecError::LengthZero : CodecError::LengthOne;
    if (length > limits::kMaxMbapLength) return CodecError::LengthTooLong;
    if (protocol_id != 0) return CodecError::BadProtocolId;
    return CodecError::Ok;
}

// Fills `out` from a complete ADU whose header has already been checked.
inline void fill_frame(const std::uint8_t* adu, std::uint16_t length, TcpFrame& out) noexcept {
    out.header.transaction_id = load_be16(adu);
    out.header.protocol_id = load_be16(adu + 2);
    out.header.length = length;
    out.header.unit_id = adu[6];
    out.pdu = Bytes(adu + limits::kMbapHeader, length - 1u);
    out.adu = Bytes(adu, length + 6u);
}

}  // namespace

MbapHeader read_mbap_header(const std::uint8_t* p) noexcept {
    MbapHeader h;
    h.transaction_id = load_be16(p);
    h.protocol_id = load_be16(p + 2);
    h.length = load_be16(p + 4);
    h.unit_id = p[6];
    return h;
}

CodecError check_mbap_header(const MbapHeader& h) noexcept {
    return check_fields(h.protocol_id, h.length);
}

CodecError decode_tcp_frame(Bytes adu, TcpFrame& out) noexcept {
    if (adu.size() < limits::kMbapHeader) {
        return adu.empty() ? CodecError::Empty : CodecError::Truncated;
    }
    const MbapHeader h = read_mbap_header(adu.data());
    out.header = h;
    out.pdu = {};
    out.adu = {};
    const CodecError e = check_mbap_header(h);
    if (e != CodecError::Ok && e != CodecError::BadProtocolId) return e;
    if (adu.size() != static_cast<std::size_t>(h.length) + 6u) return CodecError::LengthMismatch;
    fill_frame(adu.data(), h.length, out);
    return e;
}

EncodeResult encode_raw_tcp_frame(const RawMbapFields& fields, Bytes pdu,
                                  MutableBytes out) noexcept {
    const std::size_t total = limits::kMbapHeader + pdu.size();
    if (out.size() < total) return {0, CodecError::BufferTooSmall};
    std::uint8_t* p = out.data();
    if (!pdu.empty() && pdu.data() != p + limits::kMbapHeader) {
        std::memmove(p + limits::kMbapHeader, pdu.data(), pdu.size());
    }
    store_be16(p, fields.transaction_id);
    store_be16(p + 2, fields.protocol_id);
    store_be16(p + 4, fields.length);
    p[6] = fields.unit_id;
    return {total, CodecError::Ok};
}

EncodeResult encode_tcp_frame(std::uint16_t transaction_id, std::uint8_t unit_id, Bytes pdu,
                              MutableBytes out) noexcept {
    if (pdu.empty() || pdu.size() > limits::kMaxPdu) return {0, CodecError::InvalidArgument};
    const std::size_t total = limits::kMbapHeader + pdu.size();
    if (out.size() < total) return {0, CodecError::BufferTooSmall};
    std::uint8_t* p = out.data();
    // memmove: the caller may have built the PDU in place at out[7..] (then this is a no-op)
    // or somewhere overlapping.
    if (pdu.data() != p + limits::kMbapHeader) {
        std::memmove(p + limits::kMbapHeader, pdu.data(), pdu.size());
    }
    store_be16(p, transaction_id);
    store_be16(p + 2, 0);
    store_be16(p + 4, static_cast<std::uint16_t>(pdu.size() + 1));
    p[6] = unit_id;
    return {total, CodecError::Ok};
}

void MbapSplitter::feed(Bytes chunk) noexcept {
    chunk_ = chunk;
}

void MbapSplitter::reset() noexcept {
    chunk_ = {};
    partial_size_ = 0;
    error_ = CodecError::Ok;
}

namespace {

// Everything but the common case, which next() handles inline.
[[gnu::noinline]] MbapSplitter::Status next_slow(Bytes& chunk, std::uint8_t* partial,
                                                 std::size_t& partial_size, CodecError& error,
                                                 TcpFrame& out) noexcept {
    using Status = MbapSplitter::Status;
    if (error != CodecError::Ok) return Status::Fatal;
    const std::uint8_t* p = chunk.data();
    std::size_t avail = chunk.size();
    while (true) {
        if (partial_size == 0 && avail >= limits::kMbapHeader) {
            const std::uint16_t length = load_be16(p + 4);
            const CodecError e = check_fields(load_be16(p + 2), length);
            if (e != CodecError::Ok && e != CodecError::BadProtocolId) {
                error = e;
                return Status::Fatal;
            }
            const std::size_t total = length + 6u;
            if (avail >= total) {
                fill_frame(p, length, out);
                chunk = Bytes(p + total, avail - total);
                return e == CodecError::Ok ? Status::Frame : Status::BadProtocolId;
            }
        }
        if (avail == 0) return Status::NeedMore;

        // Fill the header first, then the rest of the frame once its length is known.
        std::size_t want = limits::kMbapHeader;
        if (partial_size >= limits::kMbapHeader) want = load_be16(partial + 4) + 6u;
        const std::size_t take = std::min(want - partial_size, avail);
        std::memcpy(partial + partial_size, p, take);
        partial_size += take;
        p += take;
        avail -= take;
        chunk = Bytes(p, avail);
        if (partial_size < want) return Status::NeedMore;

        // Checked as soon as the 7th header byte arrives, so errors surface early.
        const std::uint16_t length = load_be16(partial + 4);
        const CodecError e = check_fields(load_be16(partial + 2), length);
        if (e != CodecError::Ok && e != CodecError::BadProtocolId) {
            error = e;
            return Status::Fatal;
        }
        if (partial_size == length + 6u) {
            // The view into the buffer stays valid until the next call: only then can a
            // new partial frame start overwriting it.
            partial_size = 0;
            fill_frame(partial, length, out);
            return e == CodecError::Ok ? Status::Frame : Status::BadProtocolId;
        }
        // Header just completed and valid: loop to copy the body.
    }
}

}  // namespace

MbapSplitter::Status MbapSplitter::next_rest(TcpFrame& out) noexcept {
    return next_slow(chunk_, partial_.data(), partial_size_, error_, out);
}

}  // namespace mbstorm::codec
