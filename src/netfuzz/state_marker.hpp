// A death the target's state tells of: a value the fuzzer wrote into one holding register,
// read back after a case that broke a connection and cannot have written that register. Gone
// (a freshly started process holds its power-on value there), the target's process
// restarted, however fast a supervisor brought it back. For targets the idle sentinels
// (death_watch.hpp) cannot watch: one that serves one connection at a time, a serial line.
#pragma once

#include <cstdint>
#include <vector>

#include "codec/bytes.hpp"
#include "netfuzz/device_model.hpp"
#include "netfuzz/link.hpp"
#include "netfuzz/oracle.hpp"

namespace mbstorm::netfuzz {

class StateMarker {
  public:
    StateMarker(Connector& target, const TargetProfile& profile, int timeout_ms)
        : target_(target), profile_(profile), timeout_ms_(timeout_ms) {}

    // Picks the middle register of the model's largest holding range (writes must stick) and
    // writes the marker there. False when the model has none, or the write did not stick.
    bool arm(const DeviceModel& model);
    // The same at a given register (replay: the one the run used).
    bool arm_at(std::uint16_t address);
    // Writes the marker again (after a restart, or after a case that may have written it).
    bool rearm();
    bool armed() const noexcept { return armed_; }
    std::uint16_t address() const noexcept { return address_; }
    std::uint16_t initial() const noexcept { return initial_; }
    std::uint16_t value() const noexcept { return value_; }

    enum class Reading : std::uint8_t {
        Kept,        // the marker is there: no restart
        Reset,       // another value is there: the process restarted
        Unreadable,  // no answer: nothing can be said
    };
    // Reads the register on a fresh connection (`seen`: what it held). After Reset the marker
    // is disarmed: rearm() once the target is back.
    Reading read(std::uint16_t& seen);

  private:
    bool write(std::uint16_t v);
    bool read_register(std::uint16_t& out);

    Connector& target_;
    const TargetProfile& profile_;
    int timeout_ms_;
    bool armed_ = false;
    std::uint16_t address_ = 0, initial_ = 0, value_ = 0;
};

// True when the request PDU `pdu` may write holding register `address`: read conservatively
// from its raw fields (any register write whose start and quantity, valid or not, cover it),
// so that a case that wrote the marker itself is never taken for a restart.
bool may_write_register(codec::Bytes pdu, std::uint16_t address) noexcept;

}  // namespace mbstorm::netfuzz
