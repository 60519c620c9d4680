#include "codec/rtu_stream.hpp"

#include <algorithm>
#include <cstring>

#include "codec/rtu.hpp"

namespace mbstorm::codec {

namespace {

bool ends_in_its_crc(const std::uint8_t* p, std::size_t size) noexcept {
    if (size < kMinRtuAdu) return false;
    const std::uint16_t crc = crc16(Bytes(p, size - 2));
    return p[size - 2] == (crc & 0xFFu) && p[size - 1] == (crc >> 8);
}
}  // namespace

void RtuSplitter::reset() noexcept {
    chunk_ = {};
    partial_size_ = 0;
    error_ = CodecError::Ok;
}

RtuSplitter::Status RtuSplitter::emit(const std::uint8_t* adu, std::size_t size,
                                      TcpFrame& out) noexcept {
    // Every frame reaching here has its end from a length rule, or ends in its own CRC.
    const std::uint16_t crc = crc16(Bytes(adu, size - 2));
    if (adu[size - 2] != (crc & 0xFFu) || adu[size - 1] != (crc >> 8)) {
        if (skip_bad_crc_) return Status::Skipped;
        error_ = CodecError::BadCrc;
        return Status::Fatal;
    }
    out.header = MbapHeader{0, 0, static_cast<std::uint16_t>(size - 2), adu[0]};
    out.pdu = Bytes(adu + 1, size - 3);
    out.adu = Bytes(adu, size);
    return Status::Frame;
}

RtuSplitter::Status RtuSplitter::next(TcpFrame& out) noexcept {
    if (error_ != CodecError::Ok) return Status::Fatal;
    auto infer = [this](Bytes head) {
        return direction_ == Direction::Requests ? rtu_request_length(head)
                                                 : rtu_response_length(head);
    };
    // Fast path: nothing held back and a whole frame in the chunk.
    if (partial_size_ == 0 && !chunk_.empty()) {
        const RtuLength len = infer(chunk_);
        if (len.status == RtuLength::Status::Known && len.size <= chunk_.size()) {
            const std::uint8_t* p = chunk_.data();
            chunk_ = Bytes(p + len.size, chunk_.size() - len.size);
            return emit(p, len.size, out);
        }
    }
    while (!chunk_.empty()) {
        const RtuLength len = infer(Bytes(partial_.data(), partial_size_));
        std::size_t want;
        switch (len.status) {
            case RtuLength::Status::Known:
            case RtuLength::Status::NeedMore:
                want = std::max(len.size, partial_size_ + 1);
                break;
            case RtuLength::Status::TooLong:
                error_ = CodecError::FrameTooLong;
                return Status::Fatal;
            case RtuLength::Status::Unknown:
            default:
                // No length rule (an unknown function code): the frame ends at the first byte
                // after which the bytes so far end in their CRC (taken one at a time).
                want = std::min(partial_size_ + 1, limits::kMaxRtuAdu);
                break;
        }
        if (len.status == RtuLength::Status::Known && partial_size_ == len.size) break;
        if (want <= partial_size_) break;  // full: the checks below decide
        const std::size_t take = std::min(want - partial_size_, chunk_.size());
        std::memcpy(partial_.data() + partial_size_, chunk_.data(), take);
        partial_size_ += take;
        chunk_ = Bytes(chunk_.data() + take, chunk_.size() - take);
        if (len.status == RtuLength::Status::Unknown &&
            ends_in_its_crc(partial_.data(), partial_size_))
            break;
    }
    const RtuLength len = infer(Bytes(partial_.data(), partial_size_));
    if (len.status == RtuLength::Status::TooLong) {
        error_ = CodecError::FrameTooLong;
        return Status::Fatal;
    }
    if (len.status == RtuLength::Status::Known && partial_size_ == len.size) {
        partial_size_ = 0;  // the views into partial_ stay valid until the next call
        return emit(partial_.data(), len.size, out);
    }
    if (len.status == RtuLength::Status::Unknown && partial_size_ >= kMinRtuAdu) {
        if (ends_in_its_crc(partial_.data(), partial_size_)) {
            const std::size_t size = partial_size_;
            partial_size_ = 0;
            return emit(partial_.data(), size, out);
        }
        if (partial_size_ == limits::kMaxRtuAdu) {
            error_ = CodecError::BadCrc;
            return Status::Fatal;
        }
    }
    return Status::NeedMore;
}

std::size_t append_rtu_crc(std::uint8_t* out, std::size_t size) noexcept {
    const std::uint16_t crc = crc16(Bytes(out, size));
    out[size] = static_cast<std::uint8_t>(crc & 0xFFu);
    out[size + 1] = static_cast<std::uint8_t>(crc >> 8);
    return size + 2;
}

std::size_t mbap_to_rtu_in_place(std::uint8_t* adu, std::size_t size) noexcept {
    if (size < limits::kMbapHeader) return 0;
    const std::size_t pdu = size - limits::kMbapHeader;
    adu[0] = adu[6];
    std::memmove(adu + 1, adu + limits::kMbapHeader, pdu);
    return append_rtu_crc(adu, 1 + pdu);
}

void write_rtu_exception(std::uint8_t* out, std::uint8_t address, std::uint8_t function,
                         std::uint8_t code) noexcept {
    out[0] = address;
    out[1] = static_cast<std::uint8_t>(function | 0x80u);
    out[2] = code;
    append_rtu_crc(out, 3);
}

}  // namespace mbstorm::codec
