// The confirm stage of a campaign: a finding is kept only once the very case saved for it,
// replayed alone on fresh connections, shows the same fault again (what `replay` checks).
// A fault resting on a line's timing must show on every one of two runs; a silence from a
// target known to drop requests at random, on four. Whether the target drops requests at
// random is asked once, with its probe request repeated on one connection, before the first
// silence is confirmed. Every run goes through a Replayer the campaign gives, which owns the
// target (restarts, settling a hang, the deadline): this unit holds only the decisions, so it is
// tested against scripted targets with no network.
#pragma once

#include <cstdint>
#include <string>

#include "netfuzz/case.hpp"
#include "netfuzz/executor.hpp"
#include "netfuzz/finding.hpp"

namespace mbstorm::netfuzz {

// How the stage runs a case against the target.
class Replayer {
  public:
    virtual ~Replayer() = default;
    // Whether `runs` more runs fit the time left.
    virtual bool can_afford(unsigned runs) const = 0;
    // `c` run alone once on fresh connections (counted as an isolated run).
    virtual Execution replay_alone(const Case& c) = 0;
    // The target brought back if the run `ran` left it down or hung, its restart charged to
    // `cause` ("" : to nobody). False when it did not come back.
    virtual bool bring_back(const Execution& ran, const std::string& cause) = 0;
};

enum class Confirmation {
    Confirmed,
    KeptUnconfirmed,  // seen alone once; the deadline left no run to replay it (noted)
    NotShown,         // a replay did not show it: not a finding
    CutShort,         // the deadline left no run, and it cannot be kept without one
    TargetLost,       // the target did not come back
};

// A fault that rests on a line's timing (a drip, a split): `c` must show `key` on each of two
// more runs.
Confirmation shows_every_time(const Case& c, const std::string& key, Replayer& replayer);

// The probe request sent 32 times on one connection, each answer awaited: a silence there is a
// target that drops requests at random, one defect, however many other requests it swallowed.
Case random_drops_case(const TargetProfile& profile);
// Whether a verdict is that target's (dropped or closed at random).
bool drops_at_random(const Verdict& v);

class ReplayCheck {
  public:
    // Whether the target must first be asked if it drops requests at random (before the first
    // silence that is not itself that finding is confirmed).
    bool asks_random_drops_first(const Finding& f) const;
    // What the question showed: true when the target drops requests at random (its finding
    // kept).
    void random_drops_answered(bool known) noexcept;
    bool random_drops_asked() const noexcept { return asked_; }
    bool random_drops_known() const noexcept { return known_; }

    // A crash (confirmed by a second death before this) and a finding already marked
    // unconfirmed are Confirmed here as they are. KeptUnconfirmed notes why in f.note and
    // clears f.confirmed.
    Confirmation replays_alone(Finding& f, Replayer& replayer) const;

  private:
    bool asked_ = false;
    bool known_ = false;
};

}  // namespace mbstorm::netfuzz
