// The target's life across a campaign, beside the run and judge stages: telling a death that a
// supervisor hid (idle sentinel connections that all drop at once, or, where there can be
// none, a register of the map found back at its initial value) and bringing the target back
// after a crash (--restart-cmd, or waiting for its supervisor) or a whole-server hang (waiting
// until it answers again, else restarting it), each restart charged to the root cause that
// made it. What it sees goes into the campaign's result: restarts, deaths, the lost target.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "netfuzz/campaign.hpp"
#include "netfuzz/case.hpp"
#include "netfuzz/death_watch.hpp"
#include "netfuzz/executor.hpp"
#include "netfuzz/restart_command.hpp"
#include "netfuzz/state_marker.hpp"

namespace mbstorm::netfuzz {

// A hang of the whole server (every connection, fresh ones too), not of one request.
bool whole_server_hang(const Verdict& v);

class TargetCare {
  public:
    // `on_down` runs when the target is found down, before it is brought back (progress).
    TargetCare(const CampaignOptions& options, CampaignResult& result,
               std::function<void()> on_down)
        : options_(options), result_(result), on_down_(std::move(on_down)) {}
    void set_deadline(std::int64_t deadline_ns) noexcept { deadline_ns_ = deadline_ns; }

    enum class Sentinels { Armed, NotWanted, Unavailable, OneConnectionAtATime };
    // Opens the sentinels, if the target serves a fresh connection while they are open; one
    // it serves only without them serves one connection at a time (set in the profile).
    Sentinels arm_watch();
    // Where there are no sentinels: a register of the learned map keeps a value written now.
    bool arm_marker(const DeviceModel& model);
    // After a pipelined batch broke: the marker back at its initial value, when no case of
    // the batch may have written it.
    bool marker_says_restart(const std::vector<Case>& cases);
    // Whether the sentinels saw the target die (waiting up to `grace_ms` for them to close).
    bool watch_saw_death(int grace_ms);
    // Sentinels a target at its limit may have closed, and a marker lost while it hung.
    void rearm();

    // The target is down (or was found down): restart it, charging `cause` (a root-cause key,
    // or "") with the restart. False when it did not come back (the result says why).
    bool recover(const std::string& cause);
    // The target accepts but does not answer: wait for it to answer again, restarting it (a
    // death, charged to `cause`) if it never does.
    bool settle(const std::string& cause = "");
    // After a run that crashed the target or hung it as a whole: either of the above.
    bool bring_back(const Execution& ex, const std::string& cause);

    RestartCommand& restart() noexcept { return restart_; }
    DeathWatch* watch() const noexcept { return watch_.get(); }
    StateMarker* marker() const noexcept { return marker_.get(); }
    bool up() const noexcept { return up_; }
    bool settle_restarted() const noexcept { return settle_restarted_; }
    // Restarts charged to each root cause (including ones a finding had before minimising).
    void charge(const std::string& cause) { ++restarts_by_cause_[cause]; }
    unsigned charged(const std::string& cause) const;
    // Restarts charged to `from` were `to`'s (a crash blamed on the wrong request at first).
    void move_charges(const std::string& from, const std::string& to);
    const std::map<std::string, unsigned>& charges() const noexcept { return restarts_by_cause_; }

  private:
    std::int64_t remaining_ns() const;
    std::string why_not_back() const;

    const CampaignOptions& options_;
    CampaignResult& result_;
    std::function<void()> on_down_;
    std::int64_t deadline_ns_ = 0;
    RestartCommand restart_;
    std::unique_ptr<DeathWatch> watch_;
    std::unique_ptr<StateMarker> marker_;
    std::map<std::string, unsigned> restarts_by_cause_;
    bool up_ = true;
    bool settle_restarted_ = false;  // the last settle() ended in a restart
};

}  // namespace mbstorm::netfuzz
