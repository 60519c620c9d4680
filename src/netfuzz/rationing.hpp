// Rationing, between the generate and run stages: which generated cases are not sent because
// they would cost more than they can show. A device that pauses after an exception (libmodbus
// sleeps and flushes) gets each kind of request owed such an exception once, later ones of a
// kind one time in 32, and spends at most a quarter of the run in those pauses; a request to a
// unit id the device was seen not to answer (a timeout on a pipelined lane) goes one time in 16.
#pragma once

#include <cstdint>
#include <set>
#include <string>

#include "netfuzz/case.hpp"
#include "netfuzz/device_model.hpp"
#include "netfuzz/oracle.hpp"

namespace mbstorm::netfuzz {

class Rationing {
  public:
    // Whether `c` is held back, `elapsed_s` into the run. A case let through is counted as
    // sent: its kind is no longer new, its pause is spent.
    bool holds_back(const Case& c, const TargetProfile& profile, const DeviceModel& model,
                    double elapsed_s);
    std::uint64_t pause_spent_ms() const noexcept { return pause_spent_ms_; }

  private:
    bool to_silent_unit(const Case& c, const TargetProfile& profile, const DeviceModel& model);
    std::uint64_t same_kind_seen_ = 0, silent_units_seen_ = 0;
    std::set<std::string> paused_kinds_;  // kinds sent although they cost a pause
    std::uint64_t pause_spent_ms_ = 0;    // the pauses they cost, as the model measured them
};

}  // namespace mbstorm::netfuzz
