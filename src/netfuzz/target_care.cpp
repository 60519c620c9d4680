#include "netfuzz/target_care.hpp"

#include <fmt/format.h>

#include <limits>

#include "net/clock.hpp"
#include "netfuzz/culprit.hpp"
#include "netfuzz/discovery.hpp"
#include "netfuzz/rules.hpp"

namespace mbstorm::netfuzz {

bool whole_server_hang(const Verdict& v) {
    return v.oracle == Oracle::Hang && v.rule.rfind(kWholeServerHangRule, 0) == 0;
}

std::int64_t TargetCare::remaining_ns() const {
    return deadline_ns_ ? deadline_ns_ - net::now_ns() : std::numeric_limits<std::int64_t>::max();
}

unsigned TargetCare::charged(const std::string& cause) const {
    const auto it = restarts_by_cause_.find(cause);
    return it == restarts_by_cause_.end() ? 0 : it->second;
}

void TargetCare::move_charges(const std::string& from, const std::string& to) {
    const auto it = restarts_by_cause_.find(from);
    if (from == to || it == restarts_by_cause_.end()) return;
    const unsigned n = it->second;
    restarts_by_cause_.erase(it);
    restarts_by_cause_[to] += n;
}

TargetCare::Sentinels TargetCare::arm_watch() {
    // A serial line has one link; a target that serves one connection at a time would be
    // blocked by an idle one.
    Connector& target = *options_.connector;
    if (target.max_links() <= 1) return Sentinels::Unavailable;
    watch_ = std::make_unique<DeathWatch>(target, 3, options_.timeout_ms, &result_.profile);
    const auto answered = [&] {
        return probe_target(target, result_.profile, options_.timeout_ms) == ProbeResult::Ok;
    };
    // Twice: a target that drops a request now and then must neither lose its sentinels nor be
    // taken for one that serves one connection at a time over one unanswered probe.
    for (int attempt = 0; attempt < 2; ++attempt) {
        if (!watch_->arm() || !answered()) continue;
        if (!options_.death_watch) {
            watch_.reset();
            return Sentinels::NotWanted;
        }
        result_.death_watch = true;
        return Sentinels::Armed;
    }
    watch_.reset();
    // Unanswered beside idle connections, answered without them: one connection at a time.
    if (!answered() || !answered()) return Sentinels::Unavailable;
    result_.profile.one_connection = true;
    return Sentinels::OneConnectionAtATime;
}

bool TargetCare::arm_marker(const DeviceModel& model) {
    if (watch_ || !options_.death_watch || model.empty()) return false;
    marker_ =
        std::make_unique<StateMarker>(*options_.connector, result_.profile, options_.timeout_ms);
    if (!marker_->arm(model)) {
        marker_.reset();
        return false;
    }
    result_.profile.marker_address = marker_->address();
    result_.death_marker = marker_->address();
    result_.death_marker_initial = marker_->initial();
    result_.death_marker_value = marker_->value();
    return true;
}

bool TargetCare::marker_says_restart(const std::vector<Case>& cases) {
    if (!marker_ || !marker_->armed()) return false;
    for (const Case& c : cases) {
        bool wrote = false;
        for_each_request(c, result_.profile, [&](const RequestInfo& info) {
            wrote = may_write_register(info.pdu, marker_->address());
            return !wrote;
        });
        if (wrote) {
            marker_->rearm();
            return false;
        }
    }
    std::uint16_t seen = 0;
    return marker_->read(seen) == StateMarker::Reading::Reset;
}

bool TargetCare::watch_saw_death(int grace_ms) {
    return watch_ && watch_->died(grace_ms);
}

void TargetCare::rearm() {
    if (watch_ && !watch_->armed()) watch_->arm();
    if (marker_ && !marker_->armed()) marker_->rearm();
}

// Names the command and the wait: the user has to fix one of them.
std::string TargetCare::why_not_back() const {
    if (remaining_ns() <= 0) return "time limit reached while waiting for the target to come back";
    if (options_.restart_cmd.empty())
        return fmt::format(
            "the target did not come back within {} ms (--restart-wait; no --restart-cmd given)",
            options_.restart_wait_ms);
    return fmt::format(
        "the target did not come back within {} ms (--restart-wait) after --restart-cmd '{}'",
        options_.restart_wait_ms, options_.restart_cmd);
}

bool TargetCare::recover(const std::string& cause) {
    up_ = false;
    if (on_down_) on_down_();
    const std::int64_t wait_deadline = deadline_ns_ ? deadline_ns_ + 2 * net::kNsPerSec : 0;
    if (!wait_for_target_with(restart_, *options_.connector, result_.profile, options_.restart_cmd,
                              options_.restart_wait_ms, options_.timeout_ms, wait_deadline)) {
        result_.target_lost = true;
        result_.stop_reason = why_not_back();
        return false;
    }
    ++result_.restarts;
    if (!cause.empty()) charge(cause);
    up_ = true;
    // A restarted target holds none of the sentinels (those still open went to the dead
    // process) and its initial state.
    if (watch_) watch_->arm();
    if (marker_) marker_->rearm();
    return true;
}

bool TargetCare::settle(const std::string& cause) {
    settle_restarted_ = false;
    up_ = false;
    if (on_down_) on_down_();
    RestartCommand none;
    const std::int64_t wait_deadline = deadline_ns_ ? deadline_ns_ + 2 * net::kNsPerSec : 0;
    if (wait_for_target_with(none, *options_.connector, result_.profile, "",
                             options_.restart_wait_ms, options_.timeout_ms, wait_deadline)) {
        up_ = true;
        rearm();
        return true;
    }
    if (remaining_ns() <= 0) return false;
    ++result_.deaths;
    settle_restarted_ = true;
    return recover(cause);
}

bool TargetCare::bring_back(const Execution& ex, const std::string& cause) {
    if (ex.target_down) {
        ++result_.deaths;
        return recover(cause);
    }
    return !whole_server_hang(ex.verdict) || settle(cause);
}

}  // namespace mbstorm::netfuzz
