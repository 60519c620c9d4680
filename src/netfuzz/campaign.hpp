// The campaign loop: discover the target, generate cases, run them (pipelined lanes for the
// well-framed ones, one by one for the rest and for every suspect), keep findings
// (deduplicated by oracle, function code and mutation class), survive crashes by waiting for
// the target to come back, and stop at --cases or --seconds.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "net/socket.hpp"
#include "netfuzz/finding.hpp"

namespace mbstorm::netfuzz {

struct CampaignOptions {
    net::Endpoint target;
    std::string target_text;
    std::uint8_t unit = 1;
    std::uint64_t seed = 1;
    std::uint64_t max_cases = 0;  // 0: no bound
    double max_seconds = 0;       // 0: no bound
    int timeout_ms = 1000;
    unsigned lanes = 4;
    unsigned lane_depth = 48;  // cases per lane per round
    unsigned isolated_per_mille = 10;
    bool naive = false;  // baseline random-frame generator
    bool minimize = true;
    unsigned minimize_budget = 40;
    std::string restart_cmd;      // run (sh -c) when the target is down
    int restart_wait_ms = 15000;  // how long to wait for it to come back
    std::string out_dir;          // "" : findings are not saved
    double progress_interval_s = 1.0;
    std::atomic<bool>* stop = nullptr;  // set from a signal handler to end early
};

struct Progress {
    std::uint64_t cases = 0;
    double seconds = 0;
    double cases_per_second = 0;  // over the last interval
    std::size_t findings = 0;
    bool target_up = true;
    std::uint64_t restarts = 0;
};

struct CampaignResult {
    bool started = false;  // false: discovery failed (see error)
    std::string error;
    TargetProfile profile;
    std::vector<Finding> findings;
    std::uint64_t cases = 0;
    std::uint64_t batched_cases = 0, isolated_runs = 0;
    std::uint64_t duplicates = 0;   // findings suppressed as already known
    std::uint64_t unconfirmed = 0;  // suspects that did not reproduce alone
    std::uint64_t restarts = 0;     // times the target went down and came back
    bool target_lost = false;       // it did not come back: the run ended early
    double seconds = 0;
    double batch_seconds = 0, isolated_seconds = 0;  // where the time went
    std::string stop_reason;
    std::array<std::uint64_t, static_cast<std::size_t>(MutationClass::Count)> cases_by_class{};
};

using ProgressFn = std::function<void(const Progress&)>;
using FindingFn = std::function<void(const Finding&)>;

CampaignResult run_campaign(const CampaignOptions& options, const ProgressFn& on_progress = {},
                            const FindingFn& on_finding = {});

// Learns the probe request, the function codes the target does not support and its vendor
// extensions. False with `error` when the target does not answer at all.
bool discover_target(const net::Endpoint& target, std::uint8_t unit, int timeout_ms,
                     TargetProfile& profile, std::string& error);

// Waits (connects retried with backoff) until the target answers the probe, starting
// `restart_cmd` first when given. False when it does not come back within `wait_ms` of the
// command returning (or, for a command that keeps running, of its start plus a minute).
bool wait_for_target(const net::Endpoint& target, const TargetProfile& profile,
                     const std::string& restart_cmd, int wait_ms, int timeout_ms);

}  // namespace mbstorm::netfuzz
