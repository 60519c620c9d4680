#include "netfuzz/campaign.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <thread>
#include <utility>

#include "codec/exception_code.hpp"
#include "codec/function_code.hpp"
#include "codec/limits.hpp"
#include "codec/mbap.hpp"
#include "net/clock.hpp"
#include "netfuzz/attribute.hpp"
#include "netfuzz/batch.hpp"
#include "netfuzz/capacity.hpp"
#include "netfuzz/confirm.hpp"
#include "netfuzz/corpus.hpp"
#include "netfuzz/cross_transport.hpp"
#include "netfuzz/culprit.hpp"
#include "netfuzz/death_watch.hpp"
#include "netfuzz/device_model.hpp"
#include "netfuzz/discovery.hpp"
#include "netfuzz/generator.hpp"
#include "netfuzz/lone_killer.hpp"
#include "netfuzz/minimize.hpp"
#include "netfuzz/rationing.hpp"
#include "netfuzz/restart_command.hpp"
#include "netfuzz/rules.hpp"
#include "netfuzz/shrink.hpp"
#include "netfuzz/state_marker.hpp"
#include "netfuzz/target_care.hpp"
#include "netfuzz/wire.hpp"

namespace mbstorm::netfuzz {
namespace {

namespace lim = codec::limits;
using Pdu = std::vector<std::uint8_t>;

// A case's steps as one text, to tell corpus entries apart.
std::string steps_text(const Case& c) {
    std::string t;
    for (const Step& s : c.steps)
        t += fmt::format("{}/{}/{}/{};", op_name(s.op), s.conn, s.delay_us, to_hex(s.bytes));
    return t;
}

Pdu frame_of(const Pdu& pdu, std::uint16_t tid, std::uint8_t unit,
             codec::Framing framing = codec::Framing::Mbap) {
    return frame_pdu(pdu, tid, unit, framing);
}

// A finding about what a read shows after a write: whether it shows again depends on what the
// registers held before the case ran.
bool reads_back_state(const Verdict& v) {
    return v.oracle == Oracle::SpecDeviation && v.rule.rfind(kReadAfterWriteMismatchRule, 0) == 0;
}

// Each crash root cause may cost at most this many target restarts (finding it, confirming
// it, minimising it).
constexpr unsigned kMaxRestartsPerCause = 3;

// A rule as a folder name part: "target-down/fc0F-invalid" -> "target-down-fc0F-invalid".
// What discovery already hinted at, looked at before anything else so that a slow target
// cannot hide it behind its pauses: each valid request the target was silent to (alone, on a
// fresh connection, where the oracle can tell a function that is never answered), and the probe
// with a non-zero protocol id (which must be discarded, for every function alike).
std::vector<Case> first_looks(const TargetProfile& profile) {
    std::vector<Case> out;
    for (const Pdu& pdu : canonical_requests()) {
        if (!profile.silent[pdu[0]]) continue;
        Case c;
        c.cls = MutationClass::ValidLimits;
        c.function = pdu[0];
        c.steps.push_back(
            Step{Op::Send, 0, 0, 0, frame_of(pdu, 0x0F00 + pdu[0], profile.unit, profile.framing)});
        out.push_back(std::move(c));  // not pipelinable: runs alone
    }
    if (profile.framing != codec::Framing::Mbap) return out;  // no protocol id to set
    Case pid;
    pid.cls = MutationClass::ProtocolId;
    pid.function = profile.probe_pdu[0];
    Pdu f = frame_of(profile.probe_pdu, 0x0FFF, profile.unit);
    codec::store_be16(f.data() + 2, 0x0001);
    pid.steps.push_back(Step{Op::Send, 0, 0, 0, std::move(f)});
    out.push_back(std::move(pid));  // alone too: the first batch is the generator's alone
    return out;
}

std::string slug(std::string_view rule) {
    std::string s;
    for (char c : rule) {
        const bool keep = std::isalnum(static_cast<unsigned char>(c)) != 0;
        if (keep)
            s += c;
        else if (!s.empty() && s.back() != '-')
            s += '-';
    }
    while (!s.empty() && s.back() == '-') s.pop_back();
    return s.substr(0, 64);
}

// Where a root cause showed up: "fc03 invalid-values unit 1".
std::string variant_of(const Verdict& v, const Case& c) {
    std::string s = v.culprit_fc >= 0
                        ? codec::function_label(static_cast<std::uint8_t>(v.culprit_fc)) + " "
                        : std::string();
    s += class_name(c.cls);
    if (v.culprit_unit >= 0) s += fmt::format(" unit {}", v.culprit_unit);
    return s;
}

class Campaign : private Rerun, private Replayer, private LoneRuns {
  public:
    Campaign(const CampaignOptions& o, const ProgressFn& p, const FindingFn& f)
        : options_(o), on_progress_(p), on_finding_(f) {}
    CampaignResult run();

  private:
    enum class Outcome { Clean, Fired, Skipped, Lost };

    double elapsed() const { return static_cast<double>(net::now_ns() - start_) / 1e9; }
    bool stopped() const { return options_.stop && options_.stop->load(); }
    std::int64_t remaining_ns() const {
        return deadline_ ? deadline_ - net::now_ns() : std::numeric_limits<std::int64_t>::max();
    }
    // The finding that reaches --max-findings is minimised and saved before this turns true.
    bool enough_findings() const {
        return options_.max_findings && result_.findings.size() >= options_.max_findings;
    }
    bool out_of_budget() const {
        if (stopped() || enough_findings()) return true;
        if (options_.max_cases && result_.cases >= options_.max_cases) return true;
        return remaining_ns() <= 0;
    }
    // Whether `runs` isolated runs still fit before the deadline (each may wait a timeout for
    // the answer and another for the fresh probe).
    bool can_afford(unsigned runs) const override {
        if (stopped()) return false;
        const std::int64_t per_run =
            2 * std::int64_t{options_.timeout_ms} * net::kNsPerMs + 200 * net::kNsPerMs;
        return remaining_ns() > runs * per_run;
    }

    Finding* known(const Verdict& v);
    // A verdict as this target's behaviour explains it (see length_mismatch_close_).
    Verdict understood(Verdict v) const;
    // Runs a case alone and judges it as understood().
    Execution run_alone(const Case& c);
    // Asked once, of the first close blamed on a request of the wrong length: does the target
    // close on that frame by itself, before anything follows it?
    void ask_how_length_mismatch_closes(const Case& c);
    void hit(Finding& f, const Verdict& v, const Case& c);
    void learn_costly(const Finding& f);
    // Whether a request of `c` belongs to a handler with a known crash: then it is a hit of
    // that crash (charged its restart) and the handler is skipped from now on.
    bool known_crash_of(const Case& c);
    // Runs one case alone and records what it shows.
    // What an isolated run showed: its outcome and, when it fired, the root cause.
    struct Isolated {
        Outcome outcome = Outcome::Clean;
        Oracle oracle = Oracle::None;
        std::string key;
        bool confirmed_death = false;  // a new crash, confirmed by confirm_death
        bool operator==(Outcome o) const noexcept { return outcome == o; }
    };
    // `batch_died`: the case comes from a batch that killed the target (it has killed it once).
    Isolated isolate(Case c, bool batch_died = false);
    Outcome isolate_case(Case c, bool batch_died, Isolated& shown);
    // isolate()'s first run, again after a restart if the target was found down; false when
    // it stays down.
    bool first_isolated_run(const Case& c, Execution& ex);
    void take_coverage(const Case& c);
    bool calibrated_new(const Case& c, const CoverageSample& s);
    void note_answer_time(const Execution& ex);
    std::int64_t slowest_answer_ns_ = 0;
    void save_to_corpus(const Case& entry);
    bool resume_corpus();
    std::set<std::string> resumed_;  // resumed corpus entries not yet joined again
    std::size_t next_corpus_file_ = 0;
    bool corpus_write_failed_ = false;
    bool start_target();
    std::optional<Outcome> judge_transport_case(Case& c, Execution& ex, const Case& plain,
                                                const std::string& key);
    Outcome record_plain(const Case& plain, Execution whole);
    // LoneRuns, for find_lone_killer.
    Execution run_request_alone(const Case& c) override {
        ++result_.isolated_runs;
        return run_alone(c);
    }
    bool recover_from_death(const std::string& cause) override {
        ++result_.deaths;
        return care_.recover(cause);
    }
    bool settle_hang() override { return care_.settle(); }
    std::optional<Outcome> confirm_death(Case& c, Execution& ex, const std::string& key,
                                         bool batch_died);
    // Which request of a case of several kills the target alone (find_lone_killer). Found:
    // `c` and `ex` are now it and its run, and the deaths charged to `key` are its own.
    enum class Blame { None, Found, Known, Lost };
    Blame blame_lone_killer(Case& c, Execution& ex, const std::string& key);
    // After a run that crashed the target or hung it as a whole (TargetCare::bring_back).
    bool bring_back(const Execution& ex, const std::string& cause) override {
        return care_.bring_back(ex, cause);
    }
    // Replayer, for the confirm stage (confirm.hpp): a run alone, counted.
    Execution replay_alone(const Case& c) override;
    // A finding as first seen: the case and what it did.
    Finding found(const Case& c, Execution ex) const;
    // The confirm stage's answer as the campaign counts it: true when the finding stands.
    bool confirmed(Confirmation c);
    // Rerun, for the minimise stage (shrink.hpp): candidates run alone within the time and
    // the crash's restart budget.
    bool shows_again(const Case& candidate, Retrial& r) override;
    std::optional<Execution> run_once(const Case& c) override;
    ShrinkContext shrink_context() const;
    void record(const Case& c, Execution ex);
    bool replays_alone(Finding& f);
    void check_random_drops();
    Finding capacity_finding(const CapacityResult& cr) const;
    void record_lost_batch(const std::vector<Case>& batch);
    void keep(Finding f);
    void check_capacity_once();
    void progress(bool force);
    void set_drops_after_exception();
    void make_batch_runner();
    // Learns the device's map (or takes the user's) and saves it beside the findings.
    void know_the_device();
    // Liveness probes read the first address of the map (an answer, not an exception).
    void use_probe_inside_the_map();
    // Opens the sentinels (TargetCare::arm_watch) and lets the cases use them.
    void arm_watch();
    bool needs_concurrent_connections(const Case& c) const;
    // Runs cases alone before the generator's, counted as first looks; true when the target
    // was lost.
    bool look_first(std::vector<Case> cases, std::uint64_t& generated);

    // The stages of run().
    struct Round {
        std::vector<Case> piped, alone;
        std::size_t fresh = 0;  // drawn from the generator (the rest were queued again)
    };
    // What a batch left of the target.
    struct AfterBatch {
        bool whole_target = false;  // died or hung as a whole
        bool died = false;
        bool settled_by_restart = false;  // hung, and restarted to end it
        bool lost = false;                // never came back: the campaign ends
    };
    void start_generator();
    // Learns the map, aims the generator at it, looks first at what killed the stream while
    // learning; true when the target was lost.
    bool learn_then_look(std::uint64_t& generated);
    // Cases queued again first (unless a known crash or hang makes them pointless), then fresh.
    Round next_round(std::vector<Case>& requeue, std::uint64_t& generated);
    // A case joins the round unless it needs connections the target does not allow.
    void admit(Case c, Round& r);
    // Runs a round; false when the campaign ends (target lost, findings enough, line done).
    bool run_round(Round& r, std::vector<Case>& requeue, std::set<std::uint64_t>& requeued_once);
    void account_batch(const BatchResult& br, std::int64_t ns, std::size_t cases);
    // Known verdicts and lane breaks counted as hits; the rest: suspects to isolate.
    std::vector<std::size_t> triage(const BatchResult& br, const std::vector<Case>& piped);
    AfterBatch target_after_batch(const BatchResult& br, const std::vector<Case>& piped);
    // Each true when the target was lost.
    bool find_batch_culprit(const BatchResult& br, const std::vector<std::size_t>& suspects,
                            const std::vector<Case>& piped, const AfterBatch& after,
                            std::vector<std::size_t>& later);
    bool isolate_suspects(const std::vector<std::size_t>& suspects, const std::vector<Case>& piped);
    void finish();

    const CampaignOptions& options_;
    const ProgressFn& on_progress_;
    const FindingFn& on_finding_;
    CampaignResult result_;
    std::int64_t start_ = 0, deadline_ = 0;
    std::map<std::string, std::size_t> by_key_;  // root cause -> index in result_.findings
    CostlyCases costly_{result_.profile};        // not sent: they would show what is known
    std::unique_ptr<Generator> gen_;
    std::unique_ptr<BatchRunner> batch_;
    TargetCare care_{options_, result_, [this] { progress(true); }};  // deaths, restarts
    ExecOptions exec_;
    std::int64_t last_progress_ = 0;
    std::uint64_t last_cases_ = 0;
    bool capacity_checked_ = false;
    // How the target closes after a request of the wrong length, once asked: a close says the
    // stream was lost only if the target waited for bytes the frame did not have. One that
    // closes on the frame alone refuses the request, as it may any request it cannot use
    // (pymodbus 3.0 does both): one root cause, close-with-request-pending/invalid-request.
    LengthMismatchClose length_mismatch_close_ = LengthMismatchClose::NotAsked;
    // Whether the target drops requests at random, once asked (check_random_drops).
    ReplayCheck replay_check_;
    unsigned lane_depth_ = 48;
    unsigned lanes_ = 4;
    Rationing rationing_;  // cases not sent: they cost more than they can show
    // The case being isolated comes from a pipelined batch that killed the target.
    std::vector<Pdu> learned_killers_;  // requests after which learning lost the stream
    LearnOptions learn_options(double budget_s);
    // Refines a learned map between rounds, within kRefineShare of the time run so far; true
    // when the target was lost.
    bool refine_the_map(std::uint64_t& generated);
    void save_model() const;
    // Requests after which learning or refinement lost the stream, as cases to look at first
    // (at most 8).
    std::vector<Case> killer_cases(const std::vector<Pdu>& killers) const;
    bool refining_ = false;  // the model was learned whole: refinement goes on
    RefineCursor refine_cursor_;
    std::int64_t refine_ns_ = 0;
};

Finding* Campaign::known(const Verdict& v) {
    const auto it = by_key_.find(root_cause_key(understood(v)));
    return it == by_key_.end() ? nullptr : &result_.findings[it->second];
}

bool is_stream_lost_close(const Verdict& v) {
    return v.oracle == Oracle::UnexpectedClose && rule_stem(v.rule) == kStreamLostRule;
}

Verdict Campaign::understood(Verdict v) const {
    return understood_by(result_.profile, std::move(v));
}

Execution Campaign::run_alone(const Case& c) {
    // Confirmation and minimisation give the target a moment to act on each piece of a frame
    // (replay gives it more): a reproducer must not depend on how fast the target reacted.
    ExecOptions patient = exec_;
    patient.piece_settle_ms = 5;
    Execution ex = execute_case(c, *options_.connector, result_.profile, patient);
    ex.verdict = understood(std::move(ex.verdict));
    return ex;
}

// The frame alone, then a valid request this long after it: a target that frames by function
// code is still waiting for the missing bytes (libmodbus waits 500 ms), one that refuses the
// frame has closed (pymodbus: within a millisecond).
constexpr std::uint32_t kRefusalWaitUs = 100'000;

void Campaign::ask_how_length_mismatch_closes(const Case& c) {
    if (length_mismatch_close_ != LengthMismatchClose::NotAsked) return;
    if (result_.profile.framing != codec::Framing::Mbap) {
        length_mismatch_close_ = LengthMismatchClose::LosesTheStream;
        return;
    }
    std::vector<std::uint8_t> frame;
    for (const Step& s : c.steps) {
        if (s.op != Op::Send) continue;
        std::size_t consumed = 0;
        for (const Pdu& view : request_views(s.bytes, result_.profile.framing, consumed)) {
            RequestInfo info;
            describe_request(view, result_.profile, info);
            if (!pdu_length_mismatch(info)) continue;
            frame.assign(view.begin(), view.end());
            break;
        }
        if (!frame.empty()) break;
    }
    if (frame.size() <= lim::kMbapHeader || !can_afford(1)) return;  // not asked yet
    Case question;
    question.cls = MutationClass::MbapLength;
    question.function = frame[lim::kMbapHeader];
    question.number = c.number;
    question.steps.push_back(Step{Op::Send, 0, 0, 0, std::move(frame)});
    question.steps.push_back(
        Step{Op::Send, 0, kRefusalWaitUs, 0, probe_frame(result_.profile, 0x7E57)});
    ++result_.isolated_runs;
    const Execution ex = execute_case(question, *options_.connector, result_.profile, exec_);
    std::int64_t closed_us = -1, second_send_us = -1;
    int sends = 0;
    for (const TraceEvent& e : ex.trace) {
        if (e.conn != 0) continue;
        if (e.kind == TraceKind::Send && ++sends == 2) second_send_us = e.t_us;
        if ((e.kind == TraceKind::PeerClosed || e.kind == TraceKind::Reset) && closed_us < 0)
            closed_us = e.t_us;
    }
    const bool refused = closed_us >= 0 && (second_send_us < 0 || closed_us < second_send_us);
    length_mismatch_close_ =
        refused ? LengthMismatchClose::RefusesTheFrame : LengthMismatchClose::LosesTheStream;
    if (refused) {
        result_.profile.refuses_length_mismatch = true;
        costly_.length_mismatch_loses_the_stream();
    }
    bring_back(ex, "");
}

void Campaign::hit(Finding& f, const Verdict& v, const Case& c) {
    ++f.hits;
    ++f.variants[variant_of(v, c)];
    ++result_.duplicates;
    // Another request that does it: skipped from now on as well.
    if (v.oracle == Oracle::Crash || v.oracle == Oracle::Hang) {
        const std::string culprit = culprit_of(v.rule);
        if (!culprit.empty() && culprit != kCapacityCulprit) costly_.learn(culprit, c);
    }
}

bool Campaign::known_crash_of(const Case& c) {
    for (const std::string& k : signatures(c, result_.profile)) {
        const std::string culprit = k.substr(0, k.find('/'));
        const auto it = by_key_.find("crash:target-down/" + culprit);
        if (it == by_key_.end()) continue;
        Finding& f = result_.findings[it->second];
        hit(f, f.verdict, c);
        care_.charge(it->first);
        // Crashed by another kind of request too: every request of that handler is skipped.
        costly_.learn_handler(culprit);
        return true;
    }
    return false;
}

void Campaign::learn_costly(const Finding& f) {
    if (rule_stem(f.verdict.rule) == kStreamLostRule) costly_.length_mismatch_loses_the_stream();
    const Oracle o = f.oracle();
    if (o != Oracle::Crash && o != Oracle::Hang && o != Oracle::UnexpectedClose) return;
    const std::string culprit = culprit_of(f.verdict.rule);
    if (!culprit.empty() && culprit != kCapacityCulprit) {
        costly_.learn(culprit, f.fuzz_case);
        if (f.original_case.steps.size()) costly_.learn(culprit, f.original_case);
    }
    // Hangs without a culprit (stalls of other connections) are charged to their class.
    if (culprit.empty() && o == Oracle::Hang)
        gen_->deprioritise(f.fuzz_case.function, f.fuzz_case.cls);
    // A server that stalls every client while a frame is unfinished stalls them whatever the
    // frame: each case delivering one in pieces costs a timeout to show it again.
    if (f.verdict.rule == stalls_other_connections_rule(kPartialFrameCulprit))
        for (unsigned fc = 0; fc < 256; ++fc)
            for (const MutationClass cls : {MutationClass::Split, MutationClass::BurstSplit,
                                            MutationClass::PartialHold, MutationClass::Drip})
                gen_->deprioritise(static_cast<std::uint8_t>(fc), cls);
    if (f.verdict.rule == kDropsRequestsAfterExceptionRule) set_drops_after_exception();
}

void Campaign::set_drops_after_exception() {
    if (result_.profile.drops_after_exception) return;
    result_.profile.drops_after_exception = true;
    make_batch_runner();
}

// A target that drops what follows an exception usually pauses too (libmodbus sleeps its
// response timeout, server-wide): parallel lanes would only wait on each other's pauses and
// break on silence, so such a target gets one lane and short rounds (every function code is
// still reached early and progress is reported).
void Campaign::make_batch_runner() {
    const bool pauses = result_.profile.drops_after_exception;
    lanes_ = pauses || result_.profile.one_connection ? 1u : std::max(1u, options_.lanes);
    lane_depth_ = pauses ? std::min(16u, std::max(1u, options_.lane_depth))
                         : std::max(1u, options_.lane_depth);
    batch_ =
        std::make_unique<BatchRunner>(*options_.connector, result_.profile,
                                      BatchOptions{lanes_, options_.timeout_ms, pauses, deadline_});
}

// Grey-box: what the case reached. New edges (or hit counts in a new bucket) put it in the
// corpus; the constants the target compared its input against go to the generator.
void Campaign::take_coverage(const Case& c) {
    const CoverageSample s = options_.coverage->collect();
    if (s.new_bits && calibrated_new(c, s)) {
        gen_->add_to_corpus(c, s.comparisons, s.rarest_edge);
        result_.corpus_size = gen_->corpus_size();
        save_to_corpus(gen_->corpus().back());
    }
    if (s.new_edges) {
        result_.edges_by_function[c.function] += s.new_edges;
        result_.coverage_edges = options_.coverage->edges_seen();
        result_.edges_over_time.emplace_back(elapsed(), result_.coverage_edges);
    }
    if (!s.compared_words.empty() || !s.compared_bytes.empty()) {
        gen_->add_compared(s.compared_words, s.compared_bytes);
        result_.compared_constants += s.compared_words.size() + s.compared_bytes.size();
    }
}

// A case that set new bits runs 3 times more, alone (AFL's calibration), 8 when a cell changed:
// cells whose bucket changes count a loop's turns, not the input, and are left out from then on.
// False when no new bit is left in a stable cell. A run again that does not end cleanly stops
// the calibration (what it did is the next case's to find).
bool Campaign::calibrated_new(const Case& c, const CoverageSample& s) {
    constexpr int kCalibrationRuns = 3, kUnstableRuns = 8;
    CoverageMap& map = *options_.coverage;
    const std::vector<std::uint8_t> first = map.trace();
    int runs = kCalibrationRuns;
    for (int run = 0; run < runs && remaining_ns() > 0; ++run) {
        map.clear();
        const Execution again = execute_case(c, *options_.connector, result_.profile, exec_);
        ++result_.calibration_runs;
        if (again.down_before || again.target_down || again.verdict.oracle == Oracle::Hang) break;
        if (map.mark_unstable(first)) runs = kUnstableRuns;
    }
    result_.unstable_cells = map.unstable_cells();
    return map.still_new(s);
}

// RTU/ASCII: a frame owed no answer is watched for a late one 4 times as long as the slowest
// answer so far (at least 50 ms, at most the timeout), not the whole timeout: on a slave that
// answers in a millisecond, a bad-CRC case costs 50 ms, not a second.
void Campaign::note_answer_time(const Execution& ex) {
    constexpr std::int64_t kMinWatchMs = 20, kSlowestTimes = 4;
    slowest_answer_ns_ = std::max(slowest_answer_ns_, ex.slowest_answer_ns);
    if (result_.profile.framing == codec::Framing::Mbap || !slowest_answer_ns_) return;
    const std::int64_t watch_ms = kSlowestTimes * slowest_answer_ns_ / net::kNsPerMs;
    exec_.silence_watch_ms = static_cast<int>(
        std::clamp<std::int64_t>(watch_ms, kMinWatchMs, std::int64_t{options_.timeout_ms}));
}

bool Campaign::first_isolated_run(const Case& c, Execution& ex) {
    ++result_.isolated_runs;
    if (options_.coverage) options_.coverage->clear();
    ex = execute_case(c, *options_.connector, result_.profile, exec_);
    note_answer_time(ex);
    // A case that took the target down or hung it is a finding, not a corpus entry: resumed or
    // mutated, it would crash the target again, or wait out a timeout, first thing (AFL keeps
    // its timeouts out of the queue too).
    if (options_.coverage && !ex.down_before && !ex.target_down &&
        ex.verdict.oracle != Oracle::Hang)
        take_coverage(c);
    if (!ex.down_before) return true;
    // Down before this case began: whatever did it is not this case.
    ++result_.deaths;
    ++result_.unattributed_deaths;
    if (!care_.recover("")) return false;
    ex = execute_case(c, *options_.connector, result_.profile, exec_);
    if (!ex.down_before) return true;
    result_.target_lost = true;
    result_.stop_reason = "the target keeps refusing connections";
    return false;
}

// A transport case that crashed, hung or closed the target: were the frames it delivered the
// culprit, rather than the way they arrived? Sent whole, do they do the same? Nothing when the
// transport case itself is confirmed (`ex` its run again) and is to be recorded as such.
std::optional<Campaign::Outcome> Campaign::judge_transport_case(Case& c, Execution& ex,
                                                                const Case& plain,
                                                                const std::string& key) {
    if (!bring_back(ex, key)) return Outcome::Lost;
    if (!can_afford(1)) {
        ++result_.suspects_left;
        return Outcome::Clean;
    }
    ++result_.isolated_runs;
    Execution whole = run_alone(plain);
    if (whole.verdict.oracle == ex.verdict.oracle) return record_plain(plain, std::move(whole));
    if (whole.target_down) {
        ++result_.deaths;
        if (!care_.recover("")) return Outcome::Lost;
    }
    // The way the bytes arrived: confirm the transport case itself.
    if (!can_afford(1)) {
        ++result_.suspects_left;
        return Outcome::Clean;
    }
    ++result_.isolated_runs;
    ex = run_alone(c);
    if (!ex.verdict || root_cause_key(ex.verdict) != key) {
        ++result_.unconfirmed;
        if (ex.target_down) {
            ++result_.deaths;
            if (!care_.recover("")) return Outcome::Lost;
        }
        return Outcome::Clean;
    }
    if (ex.target_down) {
        ++result_.deaths;
        if (!care_.recover(key)) return Outcome::Lost;
        ex.target_down = false;  // confirmed
    }
    return std::nullopt;
}

// The frames of a transport case, sent whole, did the same: judged as the plain case (its
// death confirms a crash).
Campaign::Outcome Campaign::record_plain(const Case& plain, Execution whole) {
    const std::string key = root_cause_key(whole.verdict);
    if (Finding* f = known(whole.verdict)) {
        hit(*f, whole.verdict, plain);
        if (!bring_back(whole, key)) return Outcome::Lost;
        return Outcome::Fired;
    }
    Case blamed = plain;
    if (whole.target_down) {
        ++result_.deaths;
        care_.charge(key);  // the transport case's death was this one's too
        if (!care_.recover(key)) return Outcome::Lost;
        whole.target_down = false;  // confirmed: it killed the target twice
        switch (blame_lone_killer(blamed, whole, key)) {
            case Blame::Lost:
                return Outcome::Lost;
            case Blame::Known:
                return care_.up() ? Outcome::Fired : Outcome::Lost;
            case Blame::Found:
            case Blame::None:
                break;
        }
    } else if (whole_server_hang(whole.verdict) && !care_.settle(key)) {
        return Outcome::Lost;
    }
    record(blamed, std::move(whole));
    return care_.up() ? Outcome::Fired : Outcome::Lost;
}

// A crash is blamed on the first request left unanswered, which a target that answers a read
// in one write after the next request was never able to answer: each request alone is asked
// (one that does not kill it costs no restart), so that the crash is keyed by the request
// that does.
Campaign::Blame Campaign::blame_lone_killer(Case& c, Execution& ex, const std::string& key) {
    if (!can_afford(1)) return Blame::None;
    LoneKiller lone = find_lone_killer(c, result_.profile, *this);
    if (lone.lost) return Blame::Lost;
    if (!lone.request) return Blame::None;
    c = std::move(*lone.request);
    ex = std::move(lone.run);
    // The deaths charged to the request blamed first were this one's.
    care_.move_charges(key, root_cause_key(ex.verdict));
    Finding* f = known(ex.verdict);
    if (!f) return Blame::Found;
    hit(*f, ex.verdict, c);
    return Blame::Known;
}

// A death is a crash only if the case, replayed alone, kills the target again. Nothing when
// confirmed (`ex` the confirming run) and to be recorded. The request of several that kills
// alone is asked for first (blame_lone_killer): its death is the one confirmation would cost.
std::optional<Campaign::Outcome> Campaign::confirm_death(Case& c, Execution& ex,
                                                         const std::string& key, bool batch_died) {
    ++result_.deaths;
    if (!care_.recover(key)) {
        Finding f = found(c, std::move(ex));
        f.confirmed = false;
        f.note =
            "the target went down after this case and did not come back, so it could "
            "not be replayed to confirm it";
        keep(std::move(f));
        return Outcome::Lost;
    }
    // A case from a batch that died killed the target twice already: the batch and now, so it
    // needs no confirming run. The batch's restart is charged now, before minimisation spends
    // what is left of the budget. Its culprit is still asked for: a coalesced case blamed on
    // its first request, never answered, would file another handler's crash under it.
    if (batch_died) {
        care_.charge(key);
    } else if (!can_afford(1)) {
        ++result_.suspects_left;
        return Outcome::Clean;
    }
    switch (blame_lone_killer(c, ex, key)) {
        case Blame::Lost:
            return Outcome::Lost;
        case Blame::Known:
            return Outcome::Fired;
        case Blame::Found:
            return std::nullopt;
        case Blame::None:
            break;
    }
    if (batch_died) return std::nullopt;
    ++result_.isolated_runs;
    Execution again = run_alone(c);
    const bool same = again.verdict && root_cause_key(again.verdict) == key;
    if (!same) {
        ++result_.unattributed_deaths;
        if (again.target_down) {
            ++result_.deaths;
            if (!care_.recover("")) return Outcome::Lost;
        }
        return Outcome::Clean;
    }
    ++result_.deaths;
    if (!care_.recover(key)) {
        Finding f = found(c, std::move(again));
        f.note = "confirmed (killed the target twice); not minimised: it did not come back";
        keep(std::move(f));
        return Outcome::Lost;
    }
    ex = std::move(again);
    return std::nullopt;
}

Campaign::Isolated Campaign::isolate(Case c, bool batch_died) {
    Isolated shown;
    shown.outcome = isolate_case(std::move(c), batch_died, shown);
    return shown;
}

Campaign::Outcome Campaign::isolate_case(Case c, bool batch_died, Isolated& shown) {
    if (costly_.would_retrigger(c)) {
        ++result_.skipped_known;
        return Outcome::Skipped;
    }
    Execution ex;
    if (!first_isolated_run(c, ex)) return Outcome::Lost;
    if (!ex.verdict) return Outcome::Clean;
    if (is_stream_lost_close(ex.verdict)) {
        ask_how_length_mismatch_closes(c);
        if (!care_.up()) return Outcome::Lost;
        ex.verdict = understood(std::move(ex.verdict));
    }
    shown.oracle = ex.verdict.oracle;
    shown.key = root_cause_key(ex.verdict);
    const std::string key = shown.key;
    if (Finding* f = known(ex.verdict)) {
        hit(*f, ex.verdict, c);
        if (!bring_back(ex, key)) return Outcome::Lost;
        return Outcome::Fired;
    }
    Case plain;
    if ((ex.verdict.oracle == Oracle::Crash || ex.verdict.oracle == Oracle::Hang ||
         ex.verdict.oracle == Oracle::UnexpectedClose) &&
        is_transport_class(c.cls) && reassemble(c, plain, result_.profile.framing)) {
        if (const auto done = judge_transport_case(c, ex, plain, key)) return *done;
    }
    if (whole_server_hang(ex.verdict) && !ex.target_down && !care_.settle(key))
        return Outcome::Lost;
    if (!ex.target_down && depends_on_line_timing(c.cls) &&
        !confirmed(shows_every_time(c, key, *this)))
        return care_.up() ? Outcome::Clean : Outcome::Lost;
    if (ex.target_down) {
        const auto done = confirm_death(c, ex, key, batch_died);
        // Fired: blamed on a request that kills alone, a known crash (its death was charged).
        if (done && *done != Outcome::Fired) return *done;
        shown.key = root_cause_key(ex.verdict);  // the lone killer's, if one was found
        shown.confirmed_death = true;
        if (done) return *done;
    }
    record(c, std::move(ex));
    return care_.up() ? Outcome::Fired : Outcome::Lost;
}

Finding Campaign::found(const Case& c, Execution ex) const {
    Finding f;
    f.found_after_s = elapsed();
    f.verdict = std::move(ex.verdict);
    f.fuzz_case = f.original_case = c;
    f.case_number = c.number;
    f.trace = std::move(ex.trace);
    f.original_steps = c.steps.size();
    f.variants[variant_of(f.verdict, c)] = 1;
    return f;
}

Execution Campaign::replay_alone(const Case& c) {
    ++result_.isolated_runs;
    return run_alone(c);
}

bool Campaign::confirmed(Confirmation c) {
    switch (c) {
        case Confirmation::Confirmed:
        case Confirmation::KeptUnconfirmed:
            return true;
        case Confirmation::NotShown:
            ++result_.unconfirmed;
            return false;
        case Confirmation::CutShort:
            ++result_.suspects_left;
            return false;
        case Confirmation::TargetLost:
            return false;
    }
    return false;
}

bool Campaign::shows_again(const Case& candidate, Retrial& r) {
    if (r.lost) return false;
    if (!can_afford(1)) {
        r.cut = true;
        return false;
    }
    // One restart is kept for a batch this crash may still kill (known_crash_of).
    if (r.first.oracle == Oracle::Crash && care_.charged(r.charge) + 1 >= kMaxRestartsPerCause) {
        r.restart_budget = true;
        return false;
    }
    // A read-back's verdict depends on what the registers held before: the candidate runs
    // once to leave its own state and is judged on its second run, as a replay after it would
    // be. A step that sets the state up is then kept.
    if (reads_back_state(r.first)) {
        ++result_.isolated_runs;
        (void)run_alone(candidate);
    }
    ++result_.isolated_runs;
    Execution e = run_alone(candidate);
    // The same fault, not merely the same oracle: else it drifted to another bug (the detail
    // naming the request may change as the case shrinks: see same_fault). Field repair asks
    // for the very root cause.
    const bool same = r.same_key ? e.verdict && root_cause_key(e.verdict) == r.key
                                 : same_fault(r.first, e.verdict);
    if (e.down_before || e.target_down) {
        ++result_.deaths;
        if (!care_.recover(same && e.target_down ? r.charge : "")) r.lost = true;
    } else if (whole_server_hang(e.verdict) && !care_.settle(same ? r.charge : "")) {
        r.lost = true;
    }
    if (!same) return false;
    r.last = std::move(e);
    return true;
}

std::optional<Execution> Campaign::run_once(const Case& c) {
    if (!can_afford(1)) return std::nullopt;
    ++result_.isolated_runs;
    Execution e = run_alone(c);
    if ((e.down_before || e.target_down) && !care_.recover("")) return std::nullopt;
    return e;
}

ShrinkContext Campaign::shrink_context() const {
    return ShrinkContext{result_.model, result_.profile.framing, options_.minimize_budget,
                         kMaxRestartsPerCause};
}

void Campaign::record(const Case& c, Execution ex) {
    const std::string key = root_cause_key(ex.verdict);
    Finding f = found(c, std::move(ex));  // seen now, not when minimising it ends
    // Known from now on (its culprit), so that nothing else pays for it while it is minimised.
    learn_costly(f);
    const ShrinkContext ctx = shrink_context();
    if (options_.minimize && !minimise_finding(f, *this, ctx)) ++result_.findings_not_minimized;
    move_ranges_into_map(f, *this, ctx);
    merge_stub_answer(f, *this, ctx);
    read_back_on_writers_connection(f, *this);
    if (options_.minimize) narrow_wrong_fields(f, *this, ctx, key);
    if (!replays_alone(f)) return;
    // The identity is what the minimised reproducer violates: it may turn out to be a root
    // cause already known under another guise (a codec detail that fell away).
    if (Finding* existing = known(f.verdict)) {
        hit(*existing, f.verdict, c);
        by_key_[key] = static_cast<std::size_t>(existing - result_.findings.data());
        return;
    }
    by_key_[key] = result_.findings.size();  // the unminimised guise leads here too
    keep(std::move(f));
}

bool Campaign::replays_alone(Finding& f) {
    if (replay_check_.asks_random_drops_first(f)) check_random_drops();
    if (!care_.up()) return false;
    return confirmed(replay_check_.replays_alone(f, *this));
}

// A silence (or close) to confirm: is the request to blame, or does the target drop requests
// whatever they are? Its finding, if so, is recorded (and so confirmed) like any other.
void Campaign::check_random_drops() {
    replay_check_.random_drops_answered(false);
    if (result_.profile.probe_pdu.empty() || !can_afford(2)) return;
    const Case c = random_drops_case(result_.profile);
    Execution ex = replay_alone(c);
    if (!drops_at_random(ex.verdict)) {
        bring_back(ex, "");
        return;
    }
    // Known only once its finding is saved, i.e. replayed: a target still busy with what came
    // before (closing the capacity check's thousand connections) may leave one question
    // unanswered without dropping anything at random.
    const Verdict asked = ex.verdict;
    if (!known(asked)) record(c, std::move(ex));
    replay_check_.random_drops_answered(known(asked) != nullptr);
}

void Campaign::keep(Finding f) {
    if (f.verdict.rule == kAnswersNonzeroProtocolIdRule) result_.profile.answers_protocol_id = true;
    f.id = result_.findings.size() + 1;
    f.profile = result_.profile;
    f.target = options_.target_text;
    f.seed = options_.seed;
    f.timeout_ms = options_.timeout_ms;
    f.state = exec_.state;
    if (f.verdict.culprit_fc >= 0)
        f.fuzz_case.function = static_cast<std::uint8_t>(f.verdict.culprit_fc);
    if (!options_.out_dir.empty()) {
        const std::string dir = fmt::format("{}/{:03}-{}-{}", options_.out_dir, f.id,
                                            oracle_name(f.oracle()), slug(f.verdict.rule));
        if (const Error e = save_finding(f, dir); e.ok())
            f.folder = dir;
        else
            fmt::print(stderr, "mbstorm fuzz: {}\n", e.text());
    }
    by_key_[f.key()] = result_.findings.size();
    learn_costly(f);
    result_.findings.push_back(std::move(f));
    if (on_finding_) on_finding_(result_.findings.back());
}

void Campaign::record_lost_batch(const std::vector<Case>& batch) {
    // What the server looks like now decides crash or whole-server hang, as after one case.
    Verdict v = fresh_probe_verdict(
        probe_target(*options_.connector, result_.profile, options_.timeout_ms));
    if (!v) v = fresh_probe_verdict(ProbeResult::ConnectFailed);
    v.rule = rule_with_culprit(v.rule, kPipelinedBatchCulprit);
    Case all;
    all.cls = MutationClass::Coalesced;
    all.pipelinable = true;
    for (const Case& c : batch)
        for (Step s : c.steps) {
            s.conn = 0;
            s.delay_us = 0;
            all.steps.push_back(std::move(s));
        }
    Finding f;
    f.found_after_s = elapsed();
    f.fuzz_case = split_frames(all);  // one step per frame, the batch's order kept
    f.original_case = f.fuzz_case;
    f.case_number = batch.empty() ? 0 : batch.front().number;
    std::size_t frames = 0;
    for (const Step& s : f.fuzz_case.steps) frames += s.op == Op::Send;
    f.verdict = std::move(v);
    f.verdict.summary =
        fmt::format("{} during a pipelined batch of {} cases ({} frames) [{}]", f.verdict.summary,
                    batch.size(), frames, "unconfirmed, not minimised");
    f.confirmed = false;
    f.note = fmt::format(
        "the target went down during a pipelined batch of {} cases and did not come back, so "
        "the case that did it could not be re-run alone; unconfirmed and not minimised: the "
        "reproducer resends all {} frames of the batch in order on one connection",
        batch.size(), frames);
    f.original_steps = f.fuzz_case.steps.size();
    f.variants["pipelined batch"] = 1;
    keep(std::move(f));
}

void Campaign::check_capacity_once() {
    if (capacity_checked_ || options_.max_connections == 0 || !can_afford(4) ||
        options_.connector->max_links() <= 1)  // a serial line: one link is all there is
        return;
    capacity_checked_ = true;
    const CapacityResult cr =
        check_capacity(*options_.connector, result_.profile, options_.max_connections,
                       options_.timeout_ms, deadline_, care_.watch());
    result_.capacity_held = cr.held;
    if (cr.target_down) {
        ++result_.deaths;
        if (cr.verdict && !known(cr.verdict)) keep(capacity_finding(cr));
        care_.recover(cr.verdict ? root_cause_key(cr.verdict) : "");
        return;
    }
    if (DeathWatch* w = care_.watch()) w->arm();  // a target at its limit may have closed some
    if (!cr.verdict) return;
    // Connections left unserved: the target's own limit, or requests it drops whatever they
    // are? Asked first, and the finding kept only once its flood, replayed, shows it again.
    if (!replay_check_.random_drops_asked()) check_random_drops();
    if (replay_check_.random_drops_known() || !care_.up()) return;
    Finding f = capacity_finding(cr);
    if (!known(f.verdict) && replays_alone(f)) keep(std::move(f));
}

// The capacity check's finding: its numbers are the check's at the step that failed, and its
// reproducer opens as many connections at once as were open then.
Finding Campaign::capacity_finding(const CapacityResult& cr) const {
    Finding f;
    f.found_after_s = elapsed();
    f.verdict = cr.verdict;
    const std::uint32_t open = cr.opened ? cr.opened : cr.held + cr.refused + 64;
    const auto flood = static_cast<std::uint16_t>(std::min<std::uint32_t>(open, 0xFFFF));
    f.fuzz_case.cls = MutationClass::Flood;
    f.fuzz_case.steps.push_back(Step{Op::Flood, 0, 0, flood, {}});
    f.original_case = f.fuzz_case;
    f.original_steps = 1;
    f.variants["capacity check"] = 1;
    f.note = fmt::format(
        "found by the connection-capacity check: {} connections open at once were all "
        "answered; with {} open ({} of them refused or closed by the target, as it may) {}; "
        "the reproducer opens {} connections at once, probes each and holds them until "
        "answered",
        cr.held, cr.opened, cr.refused,
        cr.target_down ? "the target died" : "it left some unserved", flood);
    return f;
}

void Campaign::progress(bool force) {
    if (!on_progress_) return;
    const std::int64_t now = net::now_ns();
    const double dt = static_cast<double>(now - last_progress_) / 1e9;
    if (!force && dt < options_.progress_interval_s) return;
    Progress p;
    p.cases = result_.cases;
    p.seconds = elapsed();
    p.cases_per_second = dt > 0 ? static_cast<double>(result_.cases - last_cases_) / dt : 0;
    p.findings = result_.findings.size();
    p.target_up = care_.up();
    p.restarts = result_.restarts;
    last_progress_ = now;
    last_cases_ = result_.cases;
    on_progress_(p);
}

// Learning the map gets at most a tenth of the run, and never more than this.
constexpr double kLearnBudgetS = 20;

LearnOptions Campaign::learn_options(double budget_s) {
    LearnOptions lo;
    lo.timeout_ms = options_.timeout_ms;
    lo.budget_ns = static_cast<std::int64_t>(budget_s * 1e9);
    lo.hints = options_.dict_words;
    // A target learning crashed is started again by our command, if we have one.
    if (!options_.restart_cmd.empty()) lo.restart = [this] { return care_.recover(""); };
    // One request at a time on a serial line or RTU/ASCII: a coarser sweep.
    if (result_.profile.framing != codec::Framing::Mbap) lo.stride = 256;
    return lo;
}

void Campaign::know_the_device() {
    if (!options_.model.empty()) {
        result_.model = options_.model;
    } else if (options_.learn_model && !options_.naive && !result_.profile.serial_line) {
        // Not on a serial line: one request at a time at its baud rate, a sweep would take
        // most of a run (give --map there).
        const double budget_s = options_.max_seconds > 0
                                    ? std::min(options_.max_seconds / 10, kLearnBudgetS)
                                    : kLearnBudgetS;
        LearnStats st;
        result_.model =
            learn_device_model(*options_.connector, result_.profile, learn_options(budget_s), &st);
        result_.learn_seconds = st.seconds;
        result_.learn_requests = st.requests;
        learned_killers_ = std::move(st.stream_killers);
        refining_ = true;
        refine_cursor_.swept_too = result_.model.partial;
    }
    use_probe_inside_the_map();
    save_model();
}

void Campaign::save_model() const {
    if (result_.model.source.empty() || options_.out_dir.empty()) return;
    std::error_code ec;
    std::filesystem::create_directories(options_.out_dir, ec);
    std::ofstream(options_.out_dir + "/model.json") << model_to_json(result_.model);
}

// Refinement's share of the run's time so far, and its reads per turn. With 5%, libmodbus with
// a sparse map (a run spent mostly in its pauses) lost its last finding of 60 s in 2 runs of 2.
constexpr double kRefineShare = 0.02;
constexpr std::uint32_t kRefineReads = 512;

bool Campaign::refine_the_map(std::uint64_t& generated) {
    const std::int64_t t0 = net::now_ns();
    if (!refining_ || static_cast<double>(refine_ns_) > kRefineShare * (t0 - start_)) return false;
    LearnStats st;
    const double left_s = static_cast<double>(std::max<std::int64_t>(remaining_ns(), 0)) / 1e9;
    const bool changed =
        refine_device_model(*options_.connector, result_.profile, learn_options(left_s),
                            result_.model, refine_cursor_, kRefineReads, st);
    refine_ns_ += net::now_ns() - t0;
    result_.refine_seconds = static_cast<double>(refine_ns_) / 1e9;
    result_.refine_requests += st.requests;
    refining_ = !refine_cursor_.done;
    result_.refine_done = refine_cursor_.done;
    if (changed) {
        // The found ranges' neighbours were refused (a read of one owes 02), and cases aim at
        // the ranges now.
        for (std::size_t t = 0; t < kTableCount; ++t) {
            TableModel found;
            found.ranges = result_.model.tables[t].found_during_run;
            auto& out = result_.profile.unmapped[t];
            for (const std::uint16_t a : refused_neighbours(found))
                if (!result_.model.tables[t].contains(a) &&
                    std::find(out.begin(), out.end(), a) == out.end())
                    out.push_back(a);
        }
        if (!options_.state_given) exec_.state = StateRange{0, 0x10000};
        gen_->use_model(&result_.model, exec_.state);
        save_model();
    }
    std::vector<Case> killers = killer_cases(st.stream_killers);
    return !killers.empty() && look_first(std::move(killers), generated);
}

void Campaign::use_probe_inside_the_map() {
    // A learned range's neighbours were each refused alone: the oracle holds reads to that.
    if (result_.model.source == "learned" && !result_.model.partial)
        for (std::size_t t = 0; t < kTableCount; ++t) {
            const std::vector<std::uint16_t> refused = refused_neighbours(result_.model.tables[t]);
            auto& out = result_.profile.unmapped[t];
            out.insert(out.end(), refused.begin(), refused.end());
        }
    const auto probe = probe_in_map(result_.model, result_.profile.unsupported);
    if (!probe || *probe == result_.profile.probe_pdu) return;
    result_.profile.probe_pdu = *probe;
    make_batch_runner();  // it probes with the profile's request
}

void Campaign::arm_watch() {
    const TargetCare::Sentinels s = care_.arm_watch();
    if (s == TargetCare::Sentinels::Armed) exec_.watch = care_.watch();
    if (s == TargetCare::Sentinels::OneConnectionAtATime) make_batch_runner();
}

// Cases that need two connections at once (a second connection, a flood, a concurrent probe)
// show a target that serves one at a time only that: the capacity check reports it once.
bool Campaign::needs_concurrent_connections(const Case& c) const {
    if (!result_.profile.one_connection) return false;
    if (c.connections() > 1) return true;
    return std::any_of(c.steps.begin(), c.steps.end(),
                       [](const Step& s) { return s.op == Op::Flood || s.op == Op::SideProbe; });
}

bool Campaign::look_first(std::vector<Case> cases, std::uint64_t& generated) {
    for (Case& c : cases) {
        if (out_of_budget() || !can_afford(1)) break;
        if (needs_concurrent_connections(c)) {
            ++result_.not_sent_one_connection;
            continue;
        }
        c.number = ++generated;
        ++result_.cases_by_class[static_cast<std::size_t>(c.cls)];
        ++result_.cases;
        ++result_.first_looks;
        if (isolate(std::move(c)) == Outcome::Lost) return true;
    }
    return false;
}

void Campaign::start_generator() {
    GeneratorOptions go;
    go.seed = options_.seed;
    go.unit = options_.unit;
    go.naive = options_.naive;
    go.isolated_per_mille = options_.isolated_per_mille;
    // Coverage mode runs every case alone: transport and stateful cases cost no more than the
    // others there, so they get a tenth of the cases at least, as on a pausing target.
    if (options_.coverage) go.isolated_per_mille = std::max(go.isolated_per_mille, 100u);
    go.state = exec_.state;
    go.unsupported = result_.profile.unsupported;
    go.dict_words = options_.dict_words;
    go.dict_tokens = options_.dict_tokens;
    go.framing = result_.profile.framing;
    go.serial_line = result_.profile.serial_line;
    go.intercharacter_us =
        static_cast<std::uint32_t>(options_.connector->intercharacter_timeout_ns() / 1000);
    gen_ = std::make_unique<Generator>(go);
    if (options_.coverage) gen_->favour_rare_edges(options_.coverage.get());
}

bool Campaign::learn_then_look(std::uint64_t& generated) {
    know_the_device();
    // No sentinels (a target that serves one connection at a time, a serial line): a register
    // of the learned map keeps a value mbstorm wrote; back at its initial value, it restarted.
    if (care_.arm_marker(result_.model)) exec_.marker = care_.marker();
    // A known map: stateful cases write inside it, and every read-back in a case run alone
    // is checked (nothing else writes while it runs), unless the user chose the range.
    if (!result_.model.empty() && !options_.state_given) exec_.state = StateRange{0, 0x10000};
    gen_->use_model(&result_.model, exec_.state);
    // What killed the stream while learning, alone, first.
    return look_first(killer_cases(learned_killers_), generated);
}

std::vector<Case> Campaign::killer_cases(const std::vector<Pdu>& killers) const {
    std::vector<Case> out;
    for (const Pdu& pdu : killers) {
        if (out.size() == 8) break;
        out.push_back(one_request_case(pdu, result_.profile.unit, MutationClass::MapEdge, 0x0E00,
                                       result_.profile.framing));
    }
    return out;
}

Campaign::Round Campaign::next_round(std::vector<Case>& requeue, std::uint64_t& generated) {
    std::size_t n = lanes_ * lane_depth_;
    if (options_.max_cases) n = std::min<std::uint64_t>(n, options_.max_cases - result_.cases);
    Round r;
    for (Case& c : requeue) {
        // Queued before a crash or hang became known: it may carry that culprit.
        if (costly_.would_retrigger(c)) {
            ++result_.skipped_known;
            continue;
        }
        (c.pipelinable ? r.piped : r.alone).push_back(std::move(c));
    }
    requeue.clear();
    if (DeathWatch* w = care_.watch()) w->refresh();
    // Kinds that waited for the pauses' share, now that it allows them.
    for (Case& c : rationing_.release(elapsed())) {
        --result_.rationed;
        if (costly_.would_retrigger(c)) {
            ++result_.skipped_known;
            continue;
        }
        admit(std::move(c), r);
    }
    for (std::size_t tries = 0; r.piped.size() + r.alone.size() < n && tries < 8 * n; ++tries) {
        Case c;
        gen_->next(c);
        c.number = ++generated;
        if (costly_.would_retrigger(c)) {
            ++result_.skipped_known;
            continue;
        }
        if (rationing_.holds_back(c, result_.profile, result_.model, elapsed())) {
            ++result_.rationed;
            continue;
        }
        admit(std::move(c), r);
    }
    return r;
}

void Campaign::admit(Case c, Round& r) {
    if (needs_concurrent_connections(c)) {
        ++result_.not_sent_one_connection;
        return;
    }
    ++r.fresh;
    ++result_.cases_by_class[static_cast<std::size_t>(c.cls)];
    if (options_.coverage) c.pipelinable = false;  // the map is read per case
    (c.pipelinable ? r.piped : r.alone).push_back(std::move(c));
}

std::vector<std::size_t> Campaign::triage(const BatchResult& br, const std::vector<Case>& piped) {
    const auto known_verdict = [&](const Verdict& v, std::size_t ci) {
        Finding* f = known(v);
        if (f) hit(*f, v, piped[ci]);
        return f != nullptr;
    };
    const auto known_key = [&](const std::string& key, std::size_t ci) {
        const auto it = by_key_.find(key);
        if (it == by_key_.end()) return false;
        Finding& f = result_.findings[it->second];
        if (ci < piped.size()) hit(f, f.verdict, piped[ci]);
        return true;
    };
    return netfuzz::triage(br, length_mismatch_close_, known_verdict, known_key);
}

void Campaign::account_batch(const BatchResult& br, std::int64_t ns, std::size_t cases) {
    result_.batch_seconds += static_cast<double>(ns) / 1e9;
    result_.batched_cases += cases;
    result_.answers += br.answers;
    result_.busy_answers += br.busy_answers;
    // A target answering mostly 06 (busy) wastes the cases: thin the lanes and pause.
    if (br.answers >= 16 && br.busy_answers * 2 > br.answers) {
        result_.slowed_for_busy = true;
        lane_depth_ = std::max(1u, lane_depth_ / 2);
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
}

Campaign::AfterBatch Campaign::target_after_batch(const BatchResult& br,
                                                  const std::vector<Case>& piped) {
    AfterBatch after;
    const bool broke = br.connect_failed || br.lane_lost;
    // The sentinels see a death a supervisor hides from the probe below.
    const bool watched_death =
        care_.watch_saw_death(broke ? 200 : 0) || (broke && care_.marker_says_restart(piped));
    if (!broke && !watched_death) return after;
    batch_->close_all();
    const ProbeResult pr =
        watched_death ? ProbeResult::Closed
                      : probe_target(*options_.connector, result_.profile, options_.timeout_ms);
    if (pr == ProbeResult::ConnectFailed || pr == ProbeResult::Closed) {
        after.whole_target = after.died = true;
        ++result_.deaths;
        if (!care_.recover("")) {
            // Nothing can be re-run: the batch is all there is to show for it.
            if (br.lane_lost) record_lost_batch(piped);
            after.lost = true;
        }
    } else if (pr != ProbeResult::Ok) {
        after.whole_target = true;
        after.lost = !care_.settle();  // hung and never back: the suspects cannot be judged
        after.settled_by_restart = care_.settle_restarted();
    }
    return after;
}

bool Campaign::find_batch_culprit(const BatchResult& br, const std::vector<std::size_t>& suspects,
                                  const std::vector<Case>& piped, const AfterBatch& after,
                                  std::vector<std::size_t>& later) {
    bool found = false;
    for (const std::size_t ci : batch_culprit_candidates(br, suspects, piped.size())) {
        if (found || enough_findings() || !can_afford(1)) {
            later.push_back(ci);
            continue;
        }
        // A died batch holding a request of a handler known to crash: that crash explains
        // it, without killing the target again to ask.
        if (after.died && known_crash_of(piped[ci])) {
            found = true;
            continue;
        }
        const Isolated shown = isolate(piped[ci], after.died);
        if (shown == Outcome::Lost) return true;
        // A crash or hang explains the batch; anything else keeps looking.
        found = shown == Outcome::Fired &&
                (shown.oracle == Oracle::Crash || shown.oracle == Oracle::Hang);
        // The batch's death (or the hang it had to be restarted from) was this one's doing.
        // (A confirmed crash's batch death is charged by confirm_death already.)
        const bool charged = shown.oracle == Oracle::Crash && shown.confirmed_death;
        if (found && !charged && (after.died || after.settled_by_restart)) care_.charge(shown.key);
    }
    return false;
}

bool Campaign::isolate_suspects(const std::vector<std::size_t>& suspects,
                                const std::vector<Case>& piped) {
    for (std::size_t k = 0; k < suspects.size(); ++k) {
        if (enough_findings()) break;
        if (!can_afford(1)) {
            result_.suspects_left += suspects.size() - k;
            break;
        }
        const Outcome out = isolate(piped[suspects[k]]).outcome;
        if (out == Outcome::Lost) return true;
        if (out == Outcome::Clean) ++result_.unconfirmed;
    }
    return false;
}

bool Campaign::run_round(Round& r, std::vector<Case>& requeue,
                         std::set<std::uint64_t>& requeued_once) {
    const std::int64_t t0 = net::now_ns();
    const BatchResult br = batch_->run(r.piped);
    // Its lane would keep every other connection (isolated runs, probes) waiting.
    if (result_.profile.one_connection) batch_->close_all();
    const std::int64_t t1 = net::now_ns();
    account_batch(br, t1 - t0, r.piped.size());
    const std::vector<std::size_t> suspects = triage(br, r.piped);
    const AfterBatch after = target_after_batch(br, r.piped);
    if (after.lost) {
        result_.cases += r.fresh;
        return false;
    }
    std::vector<std::size_t> later;  // cases to run again in a later round
    bool lost = false;
    if (after.whole_target) {
        lost = find_batch_culprit(br, suspects, r.piped, after, later);
    } else {
        later = br.requeue;
        lost = isolate_suspects(suspects, r.piped);
    }
    for (std::size_t ci : later) {
        if (!requeued_once.insert(r.piped[ci].number).second) continue;
        ++result_.requeued;
        requeue.push_back(r.piped[ci]);
    }
    std::size_t ran_alone = 0;
    // Grey-box runs every case alone: one answer timeout left is enough to start one (a
    // suspect asks can_afford() again before it is re-run).
    const auto room_for_one = [&] {
        return options_.coverage ? remaining_ns() > options_.timeout_ms * net::kNsPerMs
                                 : can_afford(1);
    };
    for (std::size_t i = 0; !lost && i < r.alone.size(); ++i, ++ran_alone) {
        if (enough_findings() || !room_for_one()) break;
        if (isolate(r.alone[i]) == Outcome::Lost) lost = true;
    }
    result_.isolated_seconds += static_cast<double>(net::now_ns() - t1) / 1e9;
    // RTU/ASCII and grey-box: every case runs alone, so the ones the deadline left unrun were
    // not cases.
    const bool all_alone = result_.profile.framing != codec::Framing::Mbap || options_.coverage;
    result_.cases += all_alone ? std::min(r.fresh, ran_alone) : r.fresh;
    if (all_alone)
        for (std::size_t i = ran_alone; i < r.alone.size(); ++i)
            --result_.cases_by_class[static_cast<std::size_t>(r.alone[i].cls)];
    rationing_.round_took(static_cast<double>(net::now_ns() - t0) / 1e6);
    if (all_alone && ran_alone < r.alone.size() && !lost) return false;
    progress(false);
    return !lost && !enough_findings();
}

void Campaign::finish() {
    if (result_.stop_reason.empty()) {
        result_.stop_reason =
            stopped() ? "interrupted"
            : enough_findings()
                ? fmt::format("finding limit reached (--max-findings {})", options_.max_findings)
            : (options_.max_cases && result_.cases >= options_.max_cases) ? "case limit reached"
                                                                          : "time limit reached";
    }
    // Restarts per root cause, including those charged to a guise it had before minimising.
    for (const auto& [key, n] : care_.charges()) {
        const auto it = by_key_.find(key);
        if (it != by_key_.end()) result_.findings[it->second].restarts += n;
    }
    result_.seconds = elapsed();
    progress(true);
    if (options_.start_target) care_.restart().stop();
}

// --corpus DIR: a new entry is written as it joins (an entry resumed from DIR is there
// already); a write that fails ends the saving, with a note, not the run.
void Campaign::save_to_corpus(const Case& entry) {
    if (options_.corpus_dir.empty() || corpus_write_failed_) return;
    if (resumed_.erase(steps_text(entry))) return;
    if (const Error e = save_corpus_entry(options_.corpus_dir, next_corpus_file_++, entry);
        !e.ok()) {
        corpus_write_failed_ = true;
        result_.corpus_error = e.text();
    }
}

// --corpus DIR with entries from an earlier run: they run first.
bool Campaign::resume_corpus() {
    if (!options_.coverage || options_.corpus_dir.empty()) return true;
    Result<std::vector<Case>> loaded = load_corpus(options_.corpus_dir);
    if (!loaded.ok()) {
        result_.error = std::move(loaded).error();
        return false;
    }
    std::vector<Case> saved = std::move(loaded).value();
    next_corpus_file_ = saved.size();
    for (const Case& c : saved)
        resumed_.insert(steps_text(split_frames(c, options_.connector->framing())));
    result_.resumed = saved.size();
    gen_->resume(std::move(saved));
    return true;
}

// --target-cmd: the target is ours to start (and, at the end, to stop).
bool Campaign::start_target() {
    TargetProfile any;
    any.unit = options_.unit;
    any.framing = options_.connector->framing();
    any.probe_pdu = canonical_request(
        *codec::function_info(codec::to_byte(codec::FunctionCode::ReadHoldingRegisters)));
    care_.restart().own_process_group();
    if (wait_for_target_with(care_.restart(), *options_.connector, any, options_.restart_cmd,
                             options_.restart_wait_ms, options_.timeout_ms, deadline_)) {
        // Its exit is a death the executor sees on any transport (a serial line has no
        // sentinel connections).
        exec_.process_exited = [this] { return care_.restart().returned(); };
        return true;
    }
    care_.restart().stop();
    result_.error =
        Error(ErrorCode::Network,
              fmt::format("--target-cmd did not bring up a target that answers at {} within {} ms",
                          options_.connector->describe(), options_.restart_wait_ms));
    return false;
}

// The stages in order: discover, first looks, learn the device, then rounds of generated
// cases (run in pipelined batches; suspects, deaths and hangs isolated, confirmed, minimised
// and recorded) until the budget ends.
CampaignResult Campaign::run() {
    start_ = net::now_ns();
    last_progress_ = start_;
    if (options_.max_seconds > 0)
        deadline_ = start_ + static_cast<std::int64_t>(options_.max_seconds * 1e9);
    care_.set_deadline(deadline_);
    if (options_.start_target && !start_target()) return result_;
    result_.error =
        discover_target(*options_.connector, options_.unit, options_.timeout_ms, result_.profile);
    if (!result_.error.ok()) return result_;
    result_.started = true;
    result_.coverage = options_.coverage != nullptr;
    exec_.timeout_ms = options_.timeout_ms;
    exec_.state = options_.state;
    start_generator();
    if (!resume_corpus()) {
        result_.started = false;
        care_.restart().stop();
        return result_;
    }
    make_batch_runner();
    arm_watch();
    std::uint64_t generated = 0;
    // What discovery hinted at, then the other transport spoken to the port (plaintext to
    // TLS, TLS to plain), each once, alone, before the generator's cases; then the map (a slow
    // target must not hide those hints behind its learning).
    bool lost = look_first(first_looks(result_.profile), generated) ||
                look_first(cross_transport_cases(*options_.connector, result_.profile), generated);
    if (!lost && !out_of_budget()) lost = learn_then_look(generated);
    std::vector<Case> requeue;
    std::set<std::uint64_t> requeued_once;
    for (std::size_t rounds = 0; !lost && !out_of_budget();) {
        Round r = next_round(requeue, generated);
        if (!run_round(r, requeue, requeued_once)) break;
        if (++rounds == 1) check_capacity_once();
        lost = !out_of_budget() && refine_the_map(generated);
    }
    finish();
    return result_;
}

}  // namespace

std::size_t CampaignResult::new_findings() const noexcept {
    std::size_t n = 0;
    for (const Finding& f : findings) n += f.baseline != BaselineState::Known;
    return n;
}

CampaignResult run_campaign(const CampaignOptions& options, const ProgressFn& on_progress,
                            const FindingFn& on_finding) {
    Campaign c(options, on_progress, on_finding);
    return c.run();
}

}  // namespace mbstorm::netfuzz
