#include "netfuzz/confirm.hpp"

#include <fmt/format.h>

#include "netfuzz/rules.hpp"

namespace mbstorm::netfuzz {
namespace {

// A finding that rests on a line's timing counts only if this many re-runs alone repeat it.
constexpr unsigned kTimingConfirmations = 2;
// Replays a silence must pass on a target known to drop requests at random: one would pass at
// its drop rate.
constexpr unsigned kReplaysOnLossyTarget = 4;
// Times the random-drops question repeats the probe request.
constexpr std::uint16_t kProbeRepeats = 32;

bool is_silence(const Finding& f) {
    return f.oracle() == Oracle::Hang || f.oracle() == Oracle::UnexpectedClose;
}

}  // namespace

Confirmation shows_every_time(const Case& c, const std::string& key, Replayer& replayer) {
    for (unsigned run = 0; run < kTimingConfirmations; ++run) {
        if (!replayer.can_afford(1)) return Confirmation::CutShort;
        const Execution again = replayer.replay_alone(c);
        const bool same = again.verdict && root_cause_key(again.verdict) == key;
        // A restart is charged to the cause only when the run showed it.
        if (!replayer.bring_back(again, same ? key : "")) return Confirmation::TargetLost;
        if (!same) return Confirmation::NotShown;
    }
    return Confirmation::Confirmed;
}

Case random_drops_case(const TargetProfile& profile) {
    Case c;
    c.cls = MutationClass::Repeated;
    c.function = profile.probe_pdu.empty() ? 0 : profile.probe_pdu[0];
    for (std::uint16_t i = 0; i < kProbeRepeats; ++i) {
        c.steps.push_back(Step{Op::Send, 0, 0, 0, probe_frame(profile, 0x5200 + i)});
        c.steps.push_back(Step{Op::Await, 0, 0, 0, {}});
    }
    return c;
}

bool drops_at_random(const Verdict& v) {
    const std::string stem = rule_stem(v.rule);
    return stem == kRandomDropRule || stem == kRandomCloseRule;
}

bool ReplayCheck::asks_random_drops_first(const Finding& f) const {
    return !asked_ && f.oracle() != Oracle::Crash && f.confirmed && is_silence(f) &&
           !drops_at_random(f.verdict);
}

void ReplayCheck::random_drops_answered(bool known) noexcept {
    asked_ = true;
    known_ = known;
}

Confirmation ReplayCheck::replays_alone(Finding& f, Replayer& replayer) const {
    if (f.oracle() == Oracle::Crash || !f.confirmed) return Confirmation::Confirmed;
    const bool lossy = known_ && is_silence(f) && !drops_at_random(f.verdict);
    const unsigned runs = lossy ? kReplaysOnLossyTarget : 1;
    for (unsigned run = 0; run < runs; ++run) {
        if (!replayer.can_afford(1)) {
            // A silence from a target known to drop requests at random is most likely one
            // more drop: not kept unconfirmed.
            if (lossy) return Confirmation::CutShort;
            f.confirmed = false;
            f.note += fmt::format(
                "{}not confirmed: --seconds ran out before it was replayed alone once more",
                f.note.empty() ? "" : "; ");
            return Confirmation::KeptUnconfirmed;
        }
        const Execution again = replayer.replay_alone(f.fuzz_case);
        const bool same = same_fault(again.verdict, f.verdict);
        if (!replayer.bring_back(again, same ? root_cause_key(f.verdict) : ""))
            return Confirmation::TargetLost;
        if (!same) return Confirmation::NotShown;
    }
    return Confirmation::Confirmed;
}

}  // namespace mbstorm::netfuzz
