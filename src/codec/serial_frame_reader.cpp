#include "codec/serial_frame_reader.hpp"

#include <algorithm>
#include <cstring>

#include "codec/ascii.hpp"
#include "codec/rtu.hpp"

namespace mbstorm::codec {

using Result = SerialFrameReader::Result;
using ReadKind = SerialFrameReader::Result::Kind;

void SerialFrameReader::feed(Bytes data, bool after_gap) noexcept {
    if (framing_ == Framing::Rtu && after_gap && size_ != 0 && !discarding_) {
        // The inter-character timeout passed inside a frame: it is lost.
        pending_error_ = CodecError::Truncated;
        discarding_ = true;
        dropped_ = size_;
        size_ = 0;
    }
    if (discarding_) {
        dropped_ += data.size();
        return;
    }
    const std::size_t room = buf_.size() - size_;
    if (data.size() > room) {
        // Longer than any frame: a stuck transmitter or noise. Lost until the line resyncs.
        pending_error_ = CodecError::FrameTooLong;
        discarding_ = true;
        dropped_ = size_ + data.size();
        size_ = 0;
        return;
    }
    std::memcpy(buf_.data() + size_, data.data(), data.size());
    size_ += data.size();
}

Result SerialFrameReader::next(SerialFrame& frame, bool silent) noexcept {
    if (discarding_) {
        if (!silent) return {};
        // The silence ends what was being dropped; report it once.
        Result r;
        if (pending_error_ != CodecError::Ok) r = {ReadKind::Error, pending_error_, dropped_};
        discarding_ = false;
        pending_error_ = CodecError::Ok;
        dropped_ = 0;
        return r;
    }
    return framing_ == Framing::Ascii ? next_ascii(frame, silent) : next_rtu(frame, silent);
}

void SerialFrameReader::consume(std::size_t n) noexcept {
    n = std::min(n, size_);
    std::memmove(buf_.data(), buf_.data() + n, size_ - n);
    size_ -= n;
}

Result SerialFrameReader::drop_all(CodecError why) noexcept {
    Result r{ReadKind::Error, why, size_};
    size_ = 0;
    return r;
}

Result SerialFrameReader::resync(CodecError why, bool silent) noexcept {
    Result r = drop_all(why);
    // Bytes still arriving belong to the lost frame: drop them up to the next silence.
    if (!silent) discarding_ = true;
    return r;
}

Result SerialFrameReader::next_rtu(SerialFrame& frame, bool silent) noexcept {
    if (size_ == 0) return {};
    const Bytes head(buf_.data(), size_);
    const RtuLength length =
        reads_ == Reads::Requests ? rtu_request_length(head) : rtu_response_length(head);
    std::size_t frame_size = 0;
    switch (length.status) {
        case RtuLength::Status::Known:
            if (size_ < length.size) {
                if (silent) return drop_all(CodecError::Truncated);
                return {};
            }
            frame_size = length.size;
            break;
        case RtuLength::Status::NeedMore:
            if (silent) return drop_all(CodecError::Truncated);
            return {};
        case RtuLength::Status::Unknown:
            // No length rule: the silence alone ends the frame.
            if (!silent) return {};
            if (size_ > limits::kMaxRtuAdu) return drop_all(CodecError::FrameTooLong);
            frame_size = size_;
            break;
        case RtuLength::Status::TooLong:
            return resync(CodecError::FrameTooLong, silent);
    }
    std::memcpy(frame_.data(), buf_.data(), frame_size);
    RtuFrame rtu;
    const CodecError e = decode_rtu_frame(Bytes(frame_.data(), frame_size), rtu);
    if (e != CodecError::Ok) return resync(e, silent);
    consume(frame_size);
    frame.address = rtu.address;
    frame.pdu = rtu.pdu;
    frame.adu = rtu.adu;
    return {ReadKind::Frame, CodecError::Ok, 0};
}

Result SerialFrameReader::next_ascii(SerialFrame& frame, bool silent) noexcept {
    if (size_ == 0) return {};
    const std::uint8_t* begin = buf_.data();
    const std::uint8_t* end = begin + size_;
    const std::uint8_t* start = std::find(begin, end, static_cast<std::uint8_t>(':'));
    if (start != begin) {
        // Bytes outside a frame: line noise.
        const auto n = static_cast<std::size_t>(start - begin);
        consume(n);
        return {ReadKind::Error, CodecError::MissingStart, n};
    }
    const std::uint8_t* lf = std::find(begin + 1, end, static_cast<std::uint8_t>('\n'));
    const std::uint8_t* restart = std::find(begin + 1, lf, static_cast<std::uint8_t>(':'));
    if (restart != lf) {
        // A new frame began before this one ended: this one is lost.
        const auto n = static_cast<std::size_t>(restart - begin);
        consume(n);
        return {ReadKind::Error, CodecError::MissingEnd, n};
    }
    if (lf == end) {
        if (size_ > limits::kMaxAsciiAdu) return drop_all(CodecError::FrameTooLong);
        if (silent) return drop_all(CodecError::Truncated);
        return {};
    }
    const auto text_size = static_cast<std::size_t>(lf - begin) + 1;
    if (text_size > limits::kMaxAsciiAdu) {
        consume(text_size);
        return {ReadKind::Error, CodecError::FrameTooLong, text_size};
    }
    std::memcpy(frame_.data(), begin, text_size);
    consume(text_size);
    AsciiFrame ascii;
    const CodecError e = decode_ascii_frame(Bytes(frame_.data(), text_size), binary_, ascii);
    if (e != CodecError::Ok) return {ReadKind::Error, e, text_size};
    frame.address = ascii.address;
    frame.pdu = ascii.pdu;
    frame.adu = Bytes(frame_.data(), text_size);
    return {ReadKind::Frame, CodecError::Ok, 0};
}

}  // namespace mbstorm::codec
