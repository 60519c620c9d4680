// The reference slave on a serial line (`mbstorm serve --serial`): one tty, RTU or ASCII
// framing, one request at a time as on a real bus. Frames end as the serial line
// specification says (see codec/serial_frame_reader.hpp); answers keep the 3.5-character
// silence before them; broadcasts (unit 0) and frames for other units get no answer; frames
// with a bad CRC or LRC are counted and ignored, as a device on a bus must.
#pragma once

#include <atomic>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "codec/bytes.hpp"
#include "codec/framing.hpp"
#include "net/serial_port.hpp"
#include "slave/faults.hpp"
#include "slave/simulator.hpp"

namespace mbstorm::slave {
class UnitModels;
}

namespace mbstorm::server {

struct SerialServerConfig {
    std::string device;
    net::SerialSettings line;
    codec::Framing framing = codec::Framing::Rtu;
    // The models by unit id (required). Serial semantics are the caller's to set: unit 0 as
    // broadcast, unknown units silent.
    slave::UnitModels* units = nullptr;
    // Answer only this address (others are for other devices on the bus: silence).
    std::optional<std::uint8_t> only_unit;
    std::vector<slave::SimulatedInput> simulated;
    // ASCII's inter-character timeout (the specification's default is one second).
    std::int64_t ascii_timeout_ns = 1'000'000'000;
    // Fault injection as on TCP. A bus has no connection to drop: a drop is an unanswered
    // request there too. A delay holds the bus, as a slow device does.
    slave::FaultConfig faults;
};

struct SerialServerStats {
    std::uint64_t requests = 0;       // well-formed frames received
    std::uint64_t responses = 0;      // frames sent (exceptions included)
    std::uint64_t exceptions = 0;     // of which exception responses
    std::uint64_t broadcasts = 0;     // unit 0: executed, not answered
    std::uint64_t not_addressed = 0;  // for another unit: ignored
    std::uint64_t bad_checks = 0;     // CRC (RTU) or LRC (ASCII) errors
    std::uint64_t broken_frames = 0;  // truncated, overlong, broken by a silence, bad hex
    std::uint64_t noise_bytes = 0;    // bytes dropped with the above
    std::uint64_t fault_delayed = 0;  // answers held back by --delay or a stall
    std::uint64_t fault_silent = 0;   // requests left unanswered by --no-answer-rate/--drop-rate
};

class SerialServer {
  public:
    explicit SerialServer(SerialServerConfig config);
    // Opens the tty; else why not (net::SerialPort::open's errors; InvalidInput without
    // unit models).
    Error open();
    // Serves until `stop` is set (checked at least every 100 ms). Success, or the Io error
    // that ended it.
    Error run(const std::atomic<bool>& stop);
    SerialServerStats stats() const noexcept;
    std::string describe() const;

  private:
    void serve_frame(std::uint8_t address, codec::Bytes pdu);

    SerialServerConfig config_;
    net::SerialPort port_;
    slave::FaultInjector faults_;
    struct Counters {
        std::atomic<std::uint64_t> requests{0}, responses{0}, exceptions{0}, broadcasts{0},
            not_addressed{0}, bad_checks{0}, broken_frames{0}, noise_bytes{0}, fault_delayed{0},
            fault_silent{0};
    } counters_;
};

// `serve --serial`'s life: serves on a thread until SIGINT/SIGTERM (or `max_seconds`),
// printing a statistics line every second when asked, then a summary. The I/O error that
// ended it early, if one did.
Error run_serial_until_signal(SerialServer& server, bool print_stats, double max_seconds,
                              std::FILE* out);

}  // namespace mbstorm::server
