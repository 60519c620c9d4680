#include "load/serial_master.hpp"

#include <errno.h>

#include <algorithm>
#include <cstring>

#include "codec/ascii.hpp"
#include "codec/rtu.hpp"
#include "net/clock.hpp"

namespace mbstorm::load {

std::string_view serial_outcome_name(SerialOutcome o) noexcept {
    switch (o) {
        case SerialOutcome::Answered:
            return "answered";
        case SerialOutcome::Broadcast:
            return "broadcast";
        case SerialOutcome::Timeout:
            return "timeout";
        case SerialOutcome::BadCheck:
            return "bad_check";
        case SerialOutcome::BadFrame:
            return "bad_frame";
        case SerialOutcome::WrongUnit:
            return "wrong_unit";
        case SerialOutcome::IoError:
            return "io_error";
    }
    return "?";
}

Error SerialMaster::open(const std::string& device, const net::SerialSettings& settings,
                         codec::Framing framing) {
    framing_ = framing;
    reader_ = codec::SerialFrameReader(framing, codec::SerialFrameReader::Reads::Responses);
    return port_.open(device, settings);
}

std::string SerialMaster::describe() const {
    return port_.device() + " at " + net::describe(port_.settings()) + " " +
           std::string(codec::framing_name(framing_));
}

int SerialMaster::send_raw(codec::Bytes bytes, bool keep_silence) noexcept {
    const bool rtu = framing_ == codec::Framing::Rtu;
    if (!keep_silence) return port_.send_now(bytes.data(), bytes.size());
    return port_.send_frame(bytes.data(), bytes.size(),
                            rtu ? net::interframe_silence_ns(port_.settings()) : 0);
}

SerialOutcome SerialMaster::transact(std::uint8_t unit, codec::Bytes pdu, std::int64_t timeout_ns,
                                     codec::Bytes& response, std::int64_t& sent_ns) noexcept {
    const bool rtu = framing_ == codec::Framing::Rtu;
    const auto enc =
        rtu ? codec::encode_rtu_frame(unit, pdu, out_) : codec::encode_ascii_frame(unit, pdu, out_);
    if (!enc.ok()) return SerialOutcome::BadFrame;
    // Whatever arrived since the last transaction (a late answer, noise) is not this answer.
    port_.discard_input();
    reader_.reset();
    if (int rc = send_raw(codec::Bytes(out_.data(), enc.size), true); rc != 0) {
        io_error_ = -rc;
        return SerialOutcome::IoError;
    }
    sent_ns = port_.last_send_start_ns();
    if (unit == 0) {
        net::sleep_until_ns(sent_ns + turnaround_ns);
        return SerialOutcome::Broadcast;
    }
    const net::SerialSettings& line = port_.settings();
    const std::int64_t char_gap = net::intercharacter_timeout_ns(line);
    // ASCII: the specification's inter-character timeout is a second; the response timeout
    // bounds it anyway.
    const std::int64_t silence = rtu ? net::interframe_silence_ns(line) : timeout_ns;
    const std::int64_t deadline = sent_ns + timeout_ns;
    std::array<std::uint8_t, 512> chunk{};
    codec::SerialFrame frame;
    for (;;) {
        const std::int64_t now = net::now_ns();
        if (now >= deadline && !reader_.pending()) return SerialOutcome::Timeout;
        const bool waiting = reader_.pending();
        const std::int64_t wait = waiting ? silence : deadline - now;
        bool silent = false;
        if (port_.wait_readable(wait)) {
            const std::int64_t previous = port_.last_byte_received_ns();
            const ssize_t n = port_.read_some(chunk.data(), chunk.size());
            if (n < 0 && n != -EIO) {
                io_error_ = static_cast<int>(-n);
                return SerialOutcome::IoError;
            }
            if (n <= 0) {
                // EIO: the other end of a pty is gone; poll says readable until it is back.
                if (n == -EIO) net::sleep_until_ns(net::now_ns() + 5'000'000);
                continue;
            }
            const bool gap = rtu && waiting && port_.last_byte_received_ns() - previous > char_gap;
            reader_.feed(codec::Bytes(chunk.data(), static_cast<std::size_t>(n)), gap);
        } else {
            silent = waiting;
            if (!waiting) return SerialOutcome::Timeout;
        }
        const auto r = reader_.next(frame, silent);
        using Kind = codec::SerialFrameReader::Result::Kind;
        if (r.kind == Kind::None) {
            if (net::now_ns() >= deadline + silence) return SerialOutcome::Timeout;
            continue;
        }
        if (r.kind == Kind::Error)
            return r.error == codec::CodecError::BadCrc || r.error == codec::CodecError::BadLrc
                       ? SerialOutcome::BadCheck
                       : SerialOutcome::BadFrame;
        if (frame.address != unit) return SerialOutcome::WrongUnit;
        const std::size_t size = std::min(frame.pdu.size(), answer_.size());
        std::memcpy(answer_.data(), frame.pdu.data(), size);
        response = codec::Bytes(answer_.data(), size);
        return SerialOutcome::Answered;
    }
}

}  // namespace mbstorm::load
