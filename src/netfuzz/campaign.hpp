// The campaign loop: discover the target, generate cases, run them (pipelined lanes for the
// well-framed ones, one by one for the rest and for suspects), keep one finding per root cause
// (oracle and violated rule; every other case showing it is a hit with its variant), skip
// cases that would only re-trigger a known crash or hang, survive crashes by restarting the
// target, and keep --seconds as a deadline for everything, confirmation and minimisation
// included. --max-findings ends it early, once the finding that reaches it is written out.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "net/socket.hpp"
#include "netfuzz/coverage_map.hpp"
#include "netfuzz/device_model.hpp"
#include "netfuzz/discovery.hpp"
#include "netfuzz/finding.hpp"
#include "netfuzz/link.hpp"
#include "netfuzz/oracle.hpp"

namespace mbstorm::netfuzz {

struct CampaignOptions {
    std::shared_ptr<Connector> connector;  // opens links to the target (TCP, TLS, serial)
    std::string target_text;
    std::uint8_t unit = 1;
    std::uint64_t seed = 1;
    std::uint64_t max_cases = 0;   // 0: no bound
    double max_seconds = 0;        // 0: no bound
    std::size_t max_findings = 0;  // stop once this many root causes are recorded (0: no bound)
    int timeout_ms = 1000;
    unsigned lanes = 4;
    unsigned lane_depth = 48;  // cases per lane per round
    unsigned isolated_per_mille = 10;
    bool naive = false;        // baseline random-frame generator
    StateRange state;          // where stateful cases write and read back (--state-range)
    bool state_given = false;  // --state-range was given: kept even when a model is known
    // The device's map given by the user (--map, --device-model); empty: learned before fuzzing
    // (but with `naive`), within a tenth of --seconds and at most 20 s.
    DeviceModel model;
    bool learn_model = true;
    // Idle sentinel connections that tell a death a supervisor hides (netfuzz/death_watch.hpp).
    bool death_watch = true;
    std::vector<std::uint16_t> dict_words;               // --dict: 16-bit entries
    std::vector<std::vector<std::uint8_t>> dict_tokens;  // --dict: longer entries
    std::uint32_t max_connections = 4096;  // capacity oracle cap (0: no capacity check)
    bool minimize = true;
    unsigned minimize_budget = 40;
    std::string restart_cmd;  // run (sh -c) when the target is down
    // --target-cmd: restart_cmd is also run first, before discovery, and the target it runs
    // is stopped (its process group) when the campaign ends.
    bool start_target = false;
    // Grey-box (--coverage): the map the target writes its edges to. Every case then runs
    // alone (the map is cleared before it and read after), and cases that reach new edges
    // join a corpus the generator mutates. Null: black-box.
    std::shared_ptr<CoverageMap> coverage;
    // Grey-box: where the corpus is saved, one file per entry (netfuzz/corpus.hpp); the
    // entries already there are run first. "": not saved.
    std::string corpus_dir;
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
    Error error;           // why the campaign did not start (Error::none() when it did)
    TargetProfile profile;
    DeviceModel model;  // what was known of the device's map (learned or given)
    double learn_seconds = 0;
    std::uint64_t learn_requests = 0;
    // Refining the learned map during the run (refine_device_model): its reads, its time and
    // the ranges it added (model's found_during_run).
    double refine_seconds = 0;
    std::uint64_t refine_requests = 0;
    bool refine_done = false;  // every address the learning sweep stepped over was asked
    bool death_watch = false;  // sentinels were held (the target serves them concurrently)
    // Without sentinels: the holding register a marker was written to (state_marker.hpp), and
    // the values it held and was given. -1: none.
    std::int32_t death_marker = -1;
    std::uint16_t death_marker_initial = 0, death_marker_value = 0;
    std::uint64_t rationed = 0;  // cases not sent: owed an exception that costs a pause
    // Cases not sent because they need two connections at once and the target serves one at a
    // time (profile.one_connection).
    std::uint64_t not_sent_one_connection = 0;
    std::vector<Finding> findings;
    // --baseline: its file, and its root causes no finding of this run had.
    std::string baseline_file;
    std::vector<std::string> baseline_absent;
    // Findings that fail the run: all of them, or those --baseline did not know.
    std::size_t new_findings() const noexcept;
    std::uint64_t cases = 0;
    std::uint64_t batched_cases = 0, isolated_runs = 0;
    std::uint64_t duplicates = 0;     // cases that showed an already known root cause (hits)
    std::uint64_t unconfirmed = 0;    // suspects that did not reproduce alone
    std::uint64_t skipped_known = 0;  // cases not sent: they would re-trigger a known crash/hang
    std::uint64_t first_looks = 0;    // cases 1..n, alone: discovery's hints, other transport
    std::uint64_t requeued = 0;       // cases sent again after a lane broke before them
    std::uint64_t restarts = 0;       // times the target went down and came back
    std::uint64_t deaths = 0;         // times the target was seen down
    std::uint64_t unattributed_deaths = 0;        // deaths no case replayed alone could repeat
    std::uint64_t busy_answers = 0, answers = 0;  // exception 06 among pipelined answers
    bool slowed_for_busy = false;  // the target answered mostly 06: lanes were thinned
    // Cut short by the deadline: suspects never re-run, findings left unminimised.
    std::uint64_t suspects_left = 0;
    std::uint64_t findings_not_minimized = 0;
    std::uint32_t capacity_held = 0;  // most concurrent connections the capacity check held
    bool target_lost = false;         // it did not come back: the run ended early
    double seconds = 0;
    double batch_seconds = 0, isolated_seconds = 0;  // where the time went
    std::string stop_reason;
    std::array<std::uint64_t, static_cast<std::size_t>(MutationClass::Count)> cases_by_class{};
    // Grey-box runs: edges hit so far, over time (seconds, edges; a point whenever they grow),
    // the corpus, and how many constants the target's comparisons gave.
    bool coverage = false;
    std::uint32_t coverage_edges = 0;
    std::vector<std::pair<double, std::uint32_t>> edges_over_time;
    std::size_t corpus_size = 0;
    std::size_t resumed = 0;  // corpus entries loaded from --corpus and run first
    // New edges by the function code of the case that first reached them.
    std::map<std::uint8_t, std::uint32_t> edges_by_function;
    std::string corpus_error;  // why --corpus stopped being written ("": it was not)
    std::size_t compared_constants = 0;
    // Calibration: runs again of cases that set new bits, and the map cells found to change
    // between runs of one case (left out of what makes a case new).
    std::uint64_t calibration_runs = 0;
    std::uint32_t unstable_cells = 0;
};

using ProgressFn = std::function<void(const Progress&)>;
using FindingFn = std::function<void(const Finding&)>;

CampaignResult run_campaign(const CampaignOptions& options, const ProgressFn& on_progress = {},
                            const FindingFn& on_finding = {});

}  // namespace mbstorm::netfuzz
