// A serial line on a tty: raw termios at a configured baud rate, parity, data and stop bits,
// and the line's timing (character time, the 1.5 and 3.5 character silences of the Modbus
// serial line specification). Knows nothing of Modbus frames: it moves bytes and keeps the
// silence between what it sends, which a pseudo-terminal (no baud-rate timing of its own)
// would not.
#pragma once

#include <sys/types.h>

#include <cstddef>
#include <cstdint>
#include <string>

#include "net/socket.hpp"
#include "util/error.hpp"

namespace mbstorm::net {

enum class Parity : std::uint8_t { None, Even, Odd };

struct SerialSettings {
    std::uint32_t baud = 19200;
    Parity parity = Parity::Even;
    unsigned data_bits = 8;  // 7 or 8
    unsigned stop_bits = 1;  // 1 or 2
    bool operator==(const SerialSettings&) const = default;
};

// Start bit + data bits + parity bit + stop bits.
unsigned bits_per_character(const SerialSettings& s) noexcept;
// Time one character takes on the wire.
std::int64_t character_time_ns(const SerialSettings& s) noexcept;
// The inter-character timeout (t1.5) and inter-frame silence (t3.5). Above 19200 baud the
// specification fixes them at 750 us and 1.75 ms, so that fast lines do not need a
// microsecond-exact timer.
std::int64_t intercharacter_timeout_ns(const SerialSettings& s) noexcept;
std::int64_t interframe_silence_ns(const SerialSettings& s) noexcept;

// True when `device` (after symbolic links) is a pseudo-terminal: a test's line, not a bus
// with real devices on it.
bool is_pseudo_terminal(const std::string& device);

// "19200 8E1": the settings as a data sheet writes them.
std::string describe(const SerialSettings& s);

class SerialPort {
  public:
    // Opens `device` non-blocking, raw (no echo, no line discipline, no flow control) with the
    // settings. An error saying why not: Io when the device cannot be opened or set,
    // InvalidInput for a speed the tty interface lacks or a device that is not a terminal.
    Error open(const std::string& device, const SerialSettings& settings);
    bool is_open() const noexcept { return fd_.get() >= 0; }
    int fd() const noexcept { return fd_.get(); }
    const SerialSettings& settings() const noexcept { return settings_; }
    const std::string& device() const noexcept { return device_; }

    // Reads what is there (non-blocking): bytes read, 0 when nothing is waiting, -errno on an
    // error. Remembers when the last byte arrived (the start of the silence that follows).
    ssize_t read_some(std::uint8_t* data, std::size_t size) noexcept;
    // Waits up to `timeout_ns` for input; true when some is readable.
    bool wait_readable(std::int64_t timeout_ns) const noexcept;

    // Sends one frame in one piece after the line has been silent for `silence_ns` (since the
    // last byte received and since the end of the last frame sent, at the line's speed), and
    // records when this frame leaves the wire. 0 or -errno.
    int send_frame(const std::uint8_t* data, std::size_t size, std::int64_t silence_ns) noexcept;
    // Like send_frame but without waiting for any silence (the fuzzer's broken-silence case).
    int send_now(const std::uint8_t* data, std::size_t size) noexcept;

    // When the line is next free: the end of the last frame sent at the line's speed.
    std::int64_t busy_until_ns() const noexcept { return busy_until_ns_; }
    std::int64_t last_byte_received_ns() const noexcept { return last_rx_ns_; }
    // When the last frame sent started to go out (after its silence).
    std::int64_t last_send_start_ns() const noexcept { return last_send_start_ns_; }
    // Drops whatever input is waiting (a master's resynchronisation after a timeout).
    void discard_input() noexcept;

  private:
    UniqueFd fd_;
    SerialSettings settings_;
    std::string device_;
    std::int64_t busy_until_ns_ = 0;
    std::int64_t last_rx_ns_ = 0;
    std::int64_t last_send_start_ns_ = 0;
};

// Sleeps until the monotonic clock reads `deadline_ns`: a coarse sleep, then a short spin for
// the last stretch, since the silences are fractions of a millisecond.
void sleep_until_ns(std::int64_t deadline_ns) noexcept;

}  // namespace mbstorm::net
