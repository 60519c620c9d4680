// The master's side of a serial line: one request on the line at a time, the inter-frame
// silence kept before each request, the answer read with the serial framing rules and a
// response timeout. Blocking and simple: a bus carries one transaction at a time, so the
// commands (read, write, run --serial) need no ring here.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "codec/bytes.hpp"
#include "codec/framing.hpp"
#include "codec/limits.hpp"
#include "codec/serial_frame_reader.hpp"
#include "net/serial_port.hpp"
#include "util/error.hpp"

namespace mbstorm::load {

enum class SerialOutcome : std::uint8_t {
    Answered,   // `response` holds the answer's PDU
    Broadcast,  // unit 0: sent, no answer expected (the turnaround delay was kept)
    Timeout,    // no complete answer within the response timeout
    BadCheck,   // the answer's CRC (RTU) or LRC (ASCII) was wrong
    BadFrame,   // the answer was broken (truncated, overlong, bad hex, cut by a silence)
    WrongUnit,  // an answer came from another unit than the one asked
    IoError,    // the tty failed (see SerialMaster::io_error())
};

std::string_view serial_outcome_name(SerialOutcome o) noexcept;

class SerialMaster {
  public:
    // Opens the tty, or says why not (Io; the device is the error's place).
    Error open(const std::string& device, const net::SerialSettings& settings,
               codec::Framing framing);

    // Sends `pdu` to `unit` and waits up to `timeout_ns` for the answer. `response` views an
    // internal buffer, valid until the next call. `sent_ns`: when the request went out (after
    // the silence), for latency.
    SerialOutcome transact(std::uint8_t unit, codec::Bytes pdu, std::int64_t timeout_ns,
                           codec::Bytes& response, std::int64_t& sent_ns) noexcept;

    // Broadcast turnaround: how long the master waits after a unit-0 request before the next
    // (the specification suggests 100-200 ms; a test may shorten it).
    std::int64_t turnaround_ns = 100'000'000;

    int io_error() const noexcept { return io_error_; }
    const net::SerialPort& port() const noexcept { return port_; }
    std::string describe() const;

    // Sends raw bytes (the fuzzer's serial mutations): after the silence unless told not to.
    int send_raw(codec::Bytes bytes, bool keep_silence) noexcept;

  private:
    net::SerialPort port_;
    codec::Framing framing_ = codec::Framing::Rtu;
    codec::SerialFrameReader reader_{codec::Framing::Rtu,
                                     codec::SerialFrameReader::Reads::Responses};
    std::array<std::uint8_t, codec::limits::kMaxAsciiAdu> out_{};
    std::array<std::uint8_t, codec::limits::kMaxPdu> answer_{};
    int io_error_ = 0;
};

}  // namespace mbstorm::load
