// Cuts RTU frames (address, PDU, CRC-16) out of a byte stream with no other framing, as RTU
// over TCP carries them: frame ends come from the codec's length inference (rtu.hpp), and
// every frame's CRC is checked. A frame whose CRC fails ends where its length rule says it
// does, so a serial slave's manners can be kept (it drops the frame and listens on, as a slave
// behind a gateway does): with `skip_bad_crc` such a frame is skipped and the next one read.
// A frame with no length rule (an unknown function code) whose CRC fails leaves no boundary to
// resynchronise on (any byte may start the next frame): that is fatal, like a lost MBAP header.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "codec/bytes.hpp"
#include "codec/error.hpp"
#include "codec/limits.hpp"
#include "codec/mbap.hpp"

namespace mbstorm::codec {

class RtuSplitter {
  public:
    // Which side's frames the stream carries: their lengths are inferred differently.
    enum class Direction : std::uint8_t { Requests, Responses };
    enum class Status : std::uint8_t {
        Frame,     // `out` holds a complete frame with a valid CRC
        NeedMore,  // the fed bytes are used up
        Skipped,   // skip_bad_crc: a frame of known length failed its CRC and was dropped
        Fatal,     // framing lost (see error(): BadCrc, FrameTooLong); reset() before reuse
    };

    explicit RtuSplitter(Direction direction = Direction::Requests,
                         bool skip_bad_crc = false) noexcept
        : direction_(direction), skip_bad_crc_(skip_bad_crc) {}

    void feed(Bytes chunk) noexcept { chunk_ = chunk; }
    // `out` is filled as a TCP frame would be (unit id = RTU address, transaction id 0), so
    // that the same request and response code serves both framings. Its views stay valid until
    // the next call.
    Status next(TcpFrame& out) noexcept;
    CodecError error() const noexcept { return error_; }
    std::size_t buffered() const noexcept { return partial_size_; }
    std::size_t pending() const noexcept { return chunk_.size(); }
    void reset() noexcept;

  private:
    Status emit(const std::uint8_t* adu, std::size_t size, TcpFrame& out) noexcept;
    Direction direction_;
    bool skip_bad_crc_;
    Bytes chunk_;
    std::array<std::uint8_t, limits::kMaxRtuAdu> partial_{};
    std::size_t partial_size_ = 0;
    CodecError error_ = CodecError::Ok;
};

// Rewrites the MBAP ADU in `adu` (header + PDU, `size` bytes) in place as an RTU ADU (unit id,
// PDU, CRC): 4 bytes shorter. Returns the new size, 0 for a buffer shorter than a header.
std::size_t mbap_to_rtu_in_place(std::uint8_t* adu, std::size_t size) noexcept;

// Writes the RTU exception answer (address, function | 0x80, code, CRC) to `out` (5 bytes).
inline constexpr std::size_t kRtuExceptionAduSize = 5;
void write_rtu_exception(std::uint8_t* out, std::uint8_t address, std::uint8_t function,
                         std::uint8_t code) noexcept;

// Appends the CRC over out[0..size) at out[size] (low byte first). Returns size + 2.
std::size_t append_rtu_crc(std::uint8_t* out, std::size_t size) noexcept;

}  // namespace mbstorm::codec
