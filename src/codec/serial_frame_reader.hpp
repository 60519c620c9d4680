// Finds frame boundaries in the bytes a serial line delivers, RTU or ASCII, for either end of
// the line. Pure: the caller owns the clock and says when the line went silent.
//   RTU: a frame ends when the codec's length inference says it is complete, or at 3.5
//        character times of silence when the function code has no length rule; a silence of
//        more than 1.5 character times inside a frame breaks it (the specification's
//        inter-character timeout), and a broken frame is dropped at the next 3.5 silence.
//   ASCII: a frame runs from ':' to LF; bytes outside a frame are noise; a new ':' restarts.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "codec/bytes.hpp"
#include "codec/error.hpp"
#include "codec/framing.hpp"
#include "codec/limits.hpp"

namespace mbstorm::codec {

struct SerialFrame {
    std::uint8_t address = 0;
    Bytes pdu;  // function code + data
    Bytes adu;  // the frame as received (RTU: address + PDU + CRC; ASCII: ':' .. CR LF)
};

class SerialFrameReader {
  public:
    // Which frames the reader expects: a slave reads requests, a master responses (RTU's
    // length rules differ between the two).
    enum class Reads : std::uint8_t { Requests, Responses };

    struct Result {
        enum class Kind : std::uint8_t {
            None,   // nothing complete yet
            Frame,  // `frame` holds one (valid until the next call)
            Error,  // a frame was dropped: `error` says why (BadCrc, BadLrc, Truncated, ...)
        };
        Kind kind = Kind::None;
        CodecError error = CodecError::Ok;
        std::size_t dropped = 0;  // bytes dropped with an error
    };

    SerialFrameReader(Framing framing, Reads reads) noexcept : framing_(framing), reads_(reads) {}

    // Appends bytes read from the line. `after_gap`: more than 1.5 character times passed
    // since the previous byte (RTU: a frame in progress is broken).
    void feed(Bytes data, bool after_gap = false) noexcept;
    // The next frame or error in what was fed. `silent`: the line has been quiet for the
    // inter-frame silence (RTU: what is pending ends here; ASCII: a frame still open is
    // dropped as Truncated). Call until it returns None.
    Result next(SerialFrame& frame, bool silent = false) noexcept;

    // A frame is in progress or being dropped: the caller then watches for the silence.
    bool pending() const noexcept { return size_ != 0 || discarding_; }
    void reset() noexcept {
        size_ = 0;
        discarding_ = false;
        pending_error_ = CodecError::Ok;
        dropped_ = 0;
    }

  private:
    Result next_rtu(SerialFrame& frame, bool silent) noexcept;
    Result next_ascii(SerialFrame& frame, bool silent) noexcept;
    void consume(std::size_t n) noexcept;
    Result drop_all(CodecError why) noexcept;
    Result resync(CodecError why, bool silent) noexcept;

    Framing framing_;
    Reads reads_;
    // Room for one frame of the longest kind plus what a read may bring after it.
    std::array<std::uint8_t, 2 * limits::kMaxAsciiAdu> buf_{};
    std::size_t size_ = 0;
    // RTU: a frame was lost; bytes are dropped until the next silence, which then reports
    // `pending_error_` (when not reported already) with `dropped_` bytes.
    bool discarding_ = false;
    CodecError pending_error_ = CodecError::Ok;
    std::size_t dropped_ = 0;
    std::array<std::uint8_t, limits::kMaxAsciiAdu> frame_{};  // the frame handed out
    std::array<std::uint8_t, limits::kMaxRtuAdu> binary_{};   // ASCII: its decoded bytes
};

}  // namespace mbstorm::codec
