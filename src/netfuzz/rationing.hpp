// Rationing, between the generate and run stages: which generated cases are not sent because
// they would cost more than they can show. A device that pauses after an exception (libmodbus
// sleeps and flushes) gets each kind of request owed such an exception once, later ones of a
// kind one time in 32, and spends at most a quarter of the run in those pauses; a request to a
// unit id the device was seen not to answer (a timeout on a pipelined lane) goes one time in 16.
//
// A new kind waits (its first case is kept) and goes out when the share allows, fairest first:
// the function code with the fewest kinds sent, then the kind with the fewest wrong fields.
// Otherwise the commonest kinds of a few function codes take every pause (libmodbus has about 300
// kinds; a 60 s run affords 30). A round that took less than its cases were charged gives the rest
// back: a request owed 03 that the device answers 02 first (FC 05 with both its value and its
// address wrong, on libmodbus) costs no pause.
#pragma once

#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

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
    // The waiting kinds' first cases the share now affords, fairest first; counted as sent.
    // The campaign asks before each round.
    std::vector<Case> release(double elapsed_s);
    // The round the cases let through since the last call ran in took `ms`: what the pauses
    // were charged beyond that is given back.
    void round_took(double ms) noexcept;
    std::size_t waiting() const noexcept { return waiting_.size(); }
    std::uint64_t pause_spent_ms() const noexcept { return pause_spent_ms_; }

  private:
    // What a request owed a pausing exception is, for rationing.
    struct Kind {
        std::string name;              // function, the codec's reason, the wrong fields (a count:
                                       // too large or too small)
        unsigned group = 0;            // its function code; every unsupported code is one group
        std::size_t wrong = 0;         // how many of its fields are wrong
        unsigned pause_ms = 0;         // the pause the model measured after its exception
        bool length_mismatch = false;  // truncated or trailing bytes
    };
    struct Waiting {
        Kind kind;
        Case first;
        std::uint64_t order = 0;
    };
    bool to_silent_unit(const Case& c, const TargetProfile& profile, const DeviceModel& model);
    bool affordable(double elapsed_s) const noexcept;
    void send(const Kind& k);
    std::uint64_t same_kind_seen_ = 0, silent_units_seen_ = 0, waited_ = 0;
    std::set<std::string> paused_kinds_;          // kinds sent although they cost a pause
    std::map<unsigned, unsigned> sent_by_group_;  // how many kinds of each group were sent
    std::map<std::string, Waiting> waiting_;      // kinds not sent yet, by name
    std::uint64_t pause_spent_ms_ = 0;            // the pauses they cost, as the model measured
    std::uint64_t round_charge_ms_ = 0;           // the part charged in this round
};

}  // namespace mbstorm::netfuzz
