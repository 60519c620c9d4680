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
#include "netfuzz/ask.hpp"
#include "netfuzz/batch.hpp"
#include "netfuzz/capacity.hpp"
#include "netfuzz/corpus.hpp"
#include "netfuzz/cross_transport.hpp"
#include "netfuzz/culprit.hpp"
#include "netfuzz/death_watch.hpp"
#include "netfuzz/device_model.hpp"
#include "netfuzz/field_repair.hpp"
#include "netfuzz/generator.hpp"
#include "netfuzz/minimize.hpp"
#include "netfuzz/restart_command.hpp"
#include "netfuzz/rules.hpp"
#include "netfuzz/shrink.hpp"
#include "netfuzz/state_marker.hpp"
#include "netfuzz/wire.hpp"

namespace mbstorm::netfuzz {
// Defined below; the campaign keeps one RestartCommand for the whole run.
bool wait_for_target_with(RestartCommand& command, Connector& target, const TargetProfile& profile,
                          const std::string& restart_cmd, int wait_ms, int timeout_ms,
                          std::int64_t deadline_ns);

namespace {

namespace lim = codec::limits;
using Pdu = std::vector<std::uint8_t>;

// How much longer than --restart-wait a --restart-cmd that has not returned may take.
constexpr std::int64_t kRestartCommandGraceNs = 60 * net::kNsPerSec;

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

// A finding that rests on a line's timing counts only if this many re-runs alone repeat it.
constexpr unsigned kTimingConfirmations = 2;

// A finding about what a read shows after a write: whether it shows again depends on what the
// registers held before the case ran.
bool reads_back_state(const Verdict& v) {
    return v.oracle == Oracle::SpecDeviation && v.rule.rfind(kReadAfterWriteMismatchRule, 0) == 0;
}

// Each crash root cause may cost at most this many target restarts (finding it, confirming
// it, minimising it).
constexpr unsigned kMaxRestartsPerCause = 3;

// A rule as a folder name part: "target-down/fc0F-invalid" -> "target-down-fc0F-invalid".
// A valid request of every public function code (discovery asks each once): made from each
// function's request shape in the codec's table, writes aimed just below the state range.
Pdu canonical_request(const codec::FunctionInfo& info) {
    using codec::RequestShape;
    const std::uint8_t fc = codec::to_byte(info.code);
    switch (info.request) {
        case RequestShape::FunctionOnly:
            return {fc};
        case RequestShape::AddressQuantity:
            return {fc, 0, 0, 0, 1};
        case RequestShape::SingleCoil:
            return {fc, 0x5F, 0xFF, 0xFF, 0x00};
        case RequestShape::SingleRegister:
            return {fc, 0x5F, 0xFF, 0, 0};
        case RequestShape::SubFunction:
            return {fc, 0, 0, 0x12, 0x34};  // return query data
        case RequestShape::MultipleCoils:
            return {fc, 0x5F, 0xFF, 0, 1, 1, 0};
        case RequestShape::MultipleRegisters:
            return {fc, 0x5F, 0xFF, 0, 1, 2, 0, 0};
        case RequestShape::FileRecords:
            // One sub-request of record 0 in file 1: a read, or a write of one register.
            if (info.writes) return {fc, 9, 6, 0, 1, 0, 0, 0, 1, 0, 0};
            return {fc, 7, 6, 0, 1, 0, 0, 0, 1};
        case RequestShape::MaskWrite:
            return {fc, 0x5F, 0xFF, 0xFF, 0xFF, 0, 0};
        case RequestShape::ReadWriteRegisters:
            return {fc, 0, 0, 0, 1, 0x5F, 0xFF, 0, 1, 2, 0, 0};
        case RequestShape::FifoPointer:
            return {fc, 0x5F, 0xFF};
        case RequestShape::MeiTransport: {
            const std::uint8_t basic = 0x01;  // read device id code 01: the basic objects
            return {fc, codec::kMeiReadDeviceId, basic, 0x00};
        }
    }
    return {fc};
}

const std::vector<Pdu>& canonical_requests() {
    static const std::vector<Pdu> canonical = [] {
        std::vector<Pdu> out;
        for (const codec::FunctionInfo& info : codec::public_functions())
            out.push_back(canonical_request(info));
        return out;
    }();
    return canonical;
}

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

bool whole_server_hang(const Verdict& v) {
    return v.oracle == Oracle::Hang && v.rule.rfind(kWholeServerHangRule, 0) == 0;
}

class Campaign : private Rerun {
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
    bool can_afford(unsigned runs) const {
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
    bool would_retrigger(const Case& c) const;
    void learn_costly(const Finding& f);
    // Whether a request of `c` belongs to a handler with a known crash: then it is a hit of
    // that crash (charged its restart) and the handler is skipped from now on.
    bool known_crash_of(const Case& c);
    // Skips from now on the requests of `c` whose culprit is `culprit`, by signature.
    void learn_costly_signatures(const std::string& culprit, const Case& c);
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
    void save_to_corpus(const Case& entry);
    bool resume_corpus();
    std::set<std::string> resumed_;  // resumed corpus entries not yet joined again
    std::size_t next_corpus_file_ = 0;
    bool corpus_write_failed_ = false;
    bool start_target();
    std::optional<Outcome> judge_transport_case(Case& c, Execution& ex, const Case& plain,
                                                const std::string& key);
    Outcome record_plain(const Case& plain, Execution whole);
    std::optional<Outcome> confirm_death(const Case& c, Execution& ex, const std::string& key,
                                         bool batch_died);
    // The target is down (or was found down): restart it. `cause` (a root-cause key, or "")
    // is charged with the restart.
    bool recover(const std::string& cause);
    // The target accepts but does not answer (a whole-server hang): wait for it to answer
    // again before anything else is judged, restarting it if it never does.
    // A hang that outlasts --restart-wait is restarted like a crash, charged to `cause`.
    bool settle(const std::string& cause = "");
    // After a run that crashed the target or hung it as a whole: either of the above.
    bool bring_back(const Execution& ex, const std::string& cause);
    // A finding as first seen: the case and what it did.
    Finding found(const Case& c, Execution ex) const;
    bool reproduces_every_time(const Case& c, const std::string& key);
    // Rerun, for the minimise stage (shrink.hpp): candidates run alone within the time and
    // the crash's restart budget.
    bool shows_again(const Case& candidate, Retrial& r) override;
    std::optional<Execution> run_once(const Case& c) override;
    ShrinkContext shrink_context() const;
    void record(const Case& c, Execution ex);
    bool replays_alone(Finding& f);
    bool replays_once_more(const Finding& f);
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
    // Opens the sentinels, if the target serves a fresh connection while they are open.
    void arm_watch();
    bool needs_concurrent_connections(const Case& c) const;
    void arm_marker();
    bool marker_says_restart(const std::vector<Case>& cases);
    void rearm_watches();
    // Runs cases alone before the generator's, counted as first looks; true when the target
    // was lost.
    bool look_first(std::vector<Case> cases, std::uint64_t& generated);
    // Whether a case is owed an exception the target pauses after and is not sent: each kind
    // once, then 1 in 32, within a quarter of the run (kPauseShare).
    bool rationed(const Case& c);

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
    // Runs a round; false when the campaign ends (target lost, findings enough, line done).
    bool run_round(Round& r, std::vector<Case>& requeue, std::set<std::uint64_t>& requeued_once);
    void account_batch(const BatchResult& br, std::int64_t ns, std::size_t cases);
    // Root-cause keys a broken lane may be a known guise of, likeliest first.
    std::vector<std::string> lane_break_keys(const LaneBreak& b) const;
    // Known verdicts and lane breaks counted as hits; the rest: suspects to isolate.
    std::vector<std::size_t> triage(const BatchResult& br, const std::vector<Case>& piped);
    AfterBatch target_after_batch(const BatchResult& br, const std::vector<Case>& piped);
    std::vector<std::size_t> batch_culprit_candidates(const BatchResult& br,
                                                      const std::vector<std::size_t>& suspects,
                                                      std::size_t cases) const;
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
    std::set<std::string> costly_culprits_;      // culprits of known crashes and hangs
    std::map<std::string, unsigned> restarts_by_cause_;
    std::unique_ptr<Generator> gen_;
    std::unique_ptr<BatchRunner> batch_;
    std::unique_ptr<DeathWatch> watch_;
    std::unique_ptr<StateMarker> marker_;  // where there are no sentinels
    RestartCommand restart_;
    ExecOptions exec_;
    std::int64_t last_progress_ = 0;
    std::uint64_t last_cases_ = 0;
    bool up_ = true;
    bool capacity_checked_ = false;
    bool settle_restarted_ = false;  // the last settle() ended in a restart
    // A request of the wrong length is known to break the connection (the stream is lost, or
    // the target closes on such a frame): more of them only show it again.
    bool length_mismatch_known_ = false;
    // How the target closes after a request of the wrong length, once asked: a close says the
    // stream was lost only if the target waited for bytes the frame did not have. One that
    // closes on the frame alone refuses the request, as it may any request it cannot use
    // (pymodbus 3.0 does both): one root cause, close-with-request-pending/invalid-request.
    enum class LengthMismatchClose { NotAsked, RefusesTheFrame, LosesTheStream };
    LengthMismatchClose length_mismatch_close_ = LengthMismatchClose::NotAsked;
    mutable std::uint64_t length_mismatch_seen_ = 0;
    // A silence or close that did not happen again when its case was replayed: the target
    // was asked once whether it drops requests at random (check_random_drops).
    bool random_drops_asked_ = false;
    bool random_drops_known_ = false;
    unsigned lane_depth_ = 48;
    unsigned lanes_ = 4;
    std::uint64_t rationed_seen_ = 0, rationed_units_seen_ = 0;
    // Cases sent although they cost the target's pause: each kind once, the rest rationed.
    std::set<std::string> paused_kinds_;
    std::uint64_t pause_spent_ms_ = 0;  // the pauses they cost, as the model measured them
    // The case being isolated comes from a pipelined batch that killed the target.
    std::vector<Pdu> learned_killers_;  // requests after which learning lost the stream
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
    if (refused) length_mismatch_known_ = result_.profile.refuses_length_mismatch = true;
    bring_back(ex, "");
}

void Campaign::hit(Finding& f, const Verdict& v, const Case& c) {
    ++f.hits;
    ++f.variants[variant_of(v, c)];
    ++result_.duplicates;
    // Another request that does it: skipped from now on as well.
    if (v.oracle == Oracle::Crash || v.oracle == Oracle::Hang) {
        const std::string culprit = culprit_of(v.rule);
        if (!culprit.empty() && culprit != "capacity") learn_costly_signatures(culprit, c);
    }
}

bool Campaign::would_retrigger(const Case& c) const {
    // Once the target is known to lose the stream on a request of the wrong length, each such
    // request costs a broken connection (and the target's pause) to show it again: only one in
    // 16 is still sent, for what else it may hit in the handler.
    if (length_mismatch_known_ && carries_length_mismatch(c, result_.profile))
        return ++length_mismatch_seen_ % 16 != 0;
    if (costly_culprits_.empty()) return false;
    // A stateful case is about its write: its read-backs (FC 03, 01, FC 17 over the window)
    // are valid requests that would otherwise be skipped once any crash on them is known.
    const bool stateful =
        c.cls == MutationClass::StatefulSame || c.cls == MutationClass::StatefulCross;
    const std::string about = fmt::format("fc{:02X}/", c.function);
    for (const std::string& k : signatures(c, result_.profile)) {
        if (stateful && k.rfind(about, 0) != 0) continue;
        if (costly_culprits_.count(k)) return true;
        // A culprit known without a signature (a transport class, a request not framed).
        if (costly_culprits_.count(k.substr(0, k.find('/')))) return true;
    }
    return false;
}

bool Campaign::known_crash_of(const Case& c) {
    for (const std::string& k : signatures(c, result_.profile)) {
        const std::string culprit = k.substr(0, k.find('/'));
        const auto it = by_key_.find("crash:target-down/" + culprit);
        if (it == by_key_.end()) continue;
        Finding& f = result_.findings[it->second];
        hit(f, f.verdict, c);
        ++restarts_by_cause_[it->first];
        // Crashed by another kind of request too: every request of that handler is skipped.
        costly_culprits_.insert(culprit);
        return true;
    }
    return false;
}

void Campaign::learn_costly_signatures(const std::string& culprit, const Case& c) {
    bool any = false;
    for (const std::string& k : signatures(c, result_.profile))
        if (k.rfind(culprit + "/", 0) == 0) {
            costly_culprits_.insert(k);
            any = true;
        }
    if (!any) costly_culprits_.insert(culprit);
}

void Campaign::learn_costly(const Finding& f) {
    if (rule_stem(f.verdict.rule) == kStreamLostRule) length_mismatch_known_ = true;
    const Oracle o = f.oracle();
    if (o != Oracle::Crash && o != Oracle::Hang && o != Oracle::UnexpectedClose) return;
    const std::string culprit = culprit_of(f.verdict.rule);
    if (!culprit.empty() && culprit != kCapacityCulprit) {
        learn_costly_signatures(culprit, f.fuzz_case);
        if (f.original_case.steps.size()) learn_costly_signatures(culprit, f.original_case);
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

bool Campaign::recover(const std::string& cause) {
    up_ = false;
    progress(true);
    std::int64_t wait_deadline = deadline_ ? deadline_ + 2 * net::kNsPerSec : 0;
    if (!wait_for_target_with(restart_, *options_.connector, result_.profile, options_.restart_cmd,
                              options_.restart_wait_ms, options_.timeout_ms, wait_deadline)) {
        result_.target_lost = true;
        // Name the command and the wait: the user has to fix one of them.
        result_.stop_reason =
            remaining_ns() <= 0
                ? std::string("time limit reached while waiting for the target to come back")
            : options_.restart_cmd.empty()
                ? fmt::format(
                      "the target did not come back within {} ms (--restart-wait; no "
                      "--restart-cmd given)",
                      options_.restart_wait_ms)
                : fmt::format(
                      "the target did not come back within {} ms (--restart-wait) after "
                      "--restart-cmd '{}'",
                      options_.restart_wait_ms, options_.restart_cmd);
        return false;
    }
    ++result_.restarts;
    if (!cause.empty()) ++restarts_by_cause_[cause];
    up_ = true;
    // A restarted target holds none of the sentinels (those still open went to the dead
    // process) and its initial state.
    if (watch_) watch_->arm();
    if (marker_) marker_->rearm();
    return true;
}

// A settled target may have closed sentinels or lost the marker while it hung.
void Campaign::rearm_watches() {
    if (watch_ && !watch_->armed()) watch_->arm();
    if (marker_ && !marker_->armed()) marker_->rearm();
}

bool Campaign::settle(const std::string& cause) {
    settle_restarted_ = false;
    up_ = false;
    progress(true);
    RestartCommand none;
    const std::int64_t wait_deadline = deadline_ ? deadline_ + 2 * net::kNsPerSec : 0;
    if (wait_for_target_with(none, *options_.connector, result_.profile, "",
                             options_.restart_wait_ms, options_.timeout_ms, wait_deadline)) {
        up_ = true;
        rearm_watches();
        return true;
    }
    if (remaining_ns() <= 0) return false;
    ++result_.deaths;
    settle_restarted_ = true;
    return recover(cause);
}

bool Campaign::bring_back(const Execution& ex, const std::string& cause) {
    if (ex.target_down) {
        ++result_.deaths;
        return recover(cause);
    }
    return !whole_server_hang(ex.verdict) || settle(cause);
}

// Grey-box: what the case reached. New edges (or hit counts in a new bucket) put it in the
// corpus; the constants the target compared its input against go to the generator.
void Campaign::take_coverage(const Case& c) {
    const CoverageSample s = options_.coverage->collect();
    if (s.new_bits) {
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

bool Campaign::first_isolated_run(const Case& c, Execution& ex) {
    ++result_.isolated_runs;
    if (options_.coverage) options_.coverage->clear();
    ex = execute_case(c, *options_.connector, result_.profile, exec_);
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
    if (!recover("")) return false;
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
        if (!recover("")) return Outcome::Lost;
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
            if (!recover("")) return Outcome::Lost;
        }
        return Outcome::Clean;
    }
    if (ex.target_down) {
        ++result_.deaths;
        if (!recover(key)) return Outcome::Lost;
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
    if (whole.target_down) {
        ++result_.deaths;
        ++restarts_by_cause_[key];  // the transport case's death was this one's too
        if (!recover(key)) return Outcome::Lost;
        whole.target_down = false;  // confirmed: it killed the target twice
    } else if (whole_server_hang(whole.verdict) && !settle(key)) {
        return Outcome::Lost;
    }
    record(plain, std::move(whole));
    return up_ ? Outcome::Fired : Outcome::Lost;
}

// A death is a crash only if the case, replayed alone, kills the target again. Nothing when
// confirmed (`ex` the confirming run) and to be recorded.
std::optional<Campaign::Outcome> Campaign::confirm_death(const Case& c, Execution& ex,
                                                         const std::string& key, bool batch_died) {
    ++result_.deaths;
    if (!recover(key)) {
        Finding f = found(c, std::move(ex));
        f.confirmed = false;
        f.note =
            "the target went down after this case and did not come back, so it could "
            "not be replayed to confirm it";
        keep(std::move(f));
        return Outcome::Lost;
    }
    // A case from a batch that died killed the target twice already: the batch and now. The
    // batch's restart is charged now, before minimisation spends what is left of the budget.
    if (batch_died) {
        ++restarts_by_cause_[key];
        return std::nullopt;
    }
    if (!can_afford(1)) {
        ++result_.suspects_left;
        return Outcome::Clean;
    }
    ++result_.isolated_runs;
    Execution again = run_alone(c);
    const bool same = again.verdict && root_cause_key(again.verdict) == key;
    if (!same) {
        ++result_.unattributed_deaths;
        if (again.target_down) {
            ++result_.deaths;
            if (!recover("")) return Outcome::Lost;
        }
        return Outcome::Clean;
    }
    ++result_.deaths;
    if (!recover(key)) {
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
    if (would_retrigger(c)) {
        ++result_.skipped_known;
        return Outcome::Skipped;
    }
    Execution ex;
    if (!first_isolated_run(c, ex)) return Outcome::Lost;
    if (!ex.verdict) return Outcome::Clean;
    if (is_stream_lost_close(ex.verdict)) {
        ask_how_length_mismatch_closes(c);
        if (!up_) return Outcome::Lost;
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
    if (whole_server_hang(ex.verdict) && !ex.target_down && !settle(key)) return Outcome::Lost;
    if (!ex.target_down && depends_on_line_timing(c.cls) && !reproduces_every_time(c, key))
        return up_ ? Outcome::Clean : Outcome::Lost;
    if (ex.target_down)
        if (const auto done = confirm_death(c, ex, key, batch_died)) return *done;
    shown.confirmed_death = ex.target_down;
    record(c, std::move(ex));
    return up_ ? Outcome::Fired : Outcome::Lost;
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

bool Campaign::reproduces_every_time(const Case& c, const std::string& key) {
    for (unsigned run = 0; run < kTimingConfirmations; ++run) {
        if (!can_afford(1)) {
            ++result_.suspects_left;
            return false;
        }
        ++result_.isolated_runs;
        const Execution again = run_alone(c);
        const bool same = again.verdict && root_cause_key(again.verdict) == key;
        if (!bring_back(again, same ? key : "")) return false;
        if (!same) {
            ++result_.unconfirmed;
            return false;
        }
    }
    return true;
}

bool Campaign::shows_again(const Case& candidate, Retrial& r) {
    if (r.lost) return false;
    if (!can_afford(1)) {
        r.cut = true;
        return false;
    }
    // One restart is kept for a batch this crash may still kill (known_crash_of).
    if (r.first.oracle == Oracle::Crash &&
        restarts_by_cause_[r.charge] + 1 >= kMaxRestartsPerCause) {
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
        if (!recover(same && e.target_down ? r.charge : "")) r.lost = true;
    } else if (whole_server_hang(e.verdict) && !settle(same ? r.charge : "")) {
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
    if ((e.down_before || e.target_down) && !recover("")) return std::nullopt;
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

// Issue #26: a finding is saved only once the very case saved for it, run alone on fresh
// connections, shows the same fault again (what `replay` checks). A crash has killed the
// target twice by then; anything else has been seen once alone, maybe before minimisation or
// field repair changed the case, and a target that misbehaves at random shows nothing twice.
bool Campaign::replays_alone(Finding& f) {
    if (f.oracle() == Oracle::Crash || !f.confirmed) return true;
    const bool silence = f.oracle() == Oracle::Hang || f.oracle() == Oracle::UnexpectedClose;
    const bool at_random = rule_stem(f.verdict.rule) == kRandomDropRule ||
                           rule_stem(f.verdict.rule) == kRandomCloseRule;
    // Asked before the first silence is saved: a target that drops requests at random would
    // pass one replay at its drop rate, so its silences must then repeat more often before
    // each is a defect of its own.
    if (silence && !at_random && !random_drops_asked_) check_random_drops();
    if (!up_) return false;
    const unsigned runs = random_drops_known_ && silence && !at_random ? 4 : 1;
    for (unsigned run = 0; run < runs; ++run) {
        if (!can_afford(1)) {
            // A silence from a target known to drop requests at random is most likely one
            // more drop: not kept unconfirmed.
            if (runs > 1) {
                ++result_.suspects_left;
                return false;
            }
            // Seen alone once: kept, but not called confirmed.
            f.confirmed = false;
            f.note += fmt::format(
                "{}not confirmed: --seconds ran out before it was replayed "
                "alone once more",
                f.note.empty() ? "" : "; ");
            return true;
        }
        if (replays_once_more(f)) continue;
        ++result_.unconfirmed;
        return false;
    }
    return true;
}

bool Campaign::replays_once_more(const Finding& f) {
    ++result_.isolated_runs;
    const Execution e = run_alone(f.fuzz_case);
    const bool same = same_fault(e.verdict, f.verdict);
    return bring_back(e, same ? root_cause_key(f.verdict) : "") && same;
}

// A silence (or close) that did not come again when its case was replayed alone: is the
// request to blame, or does the target drop requests whatever they are? Its probe request,
// answered at discovery, is sent 32 times on one connection, each answer awaited. A silence
// there is one defect, found once, however many other requests it has swallowed.
void Campaign::check_random_drops() {
    constexpr std::uint16_t kRepeats = 32;
    random_drops_asked_ = true;
    if (result_.profile.probe_pdu.empty() || !can_afford(2)) return;
    Case c;
    c.cls = MutationClass::Repeated;
    c.function = result_.profile.probe_pdu[0];
    for (std::uint16_t i = 0; i < kRepeats; ++i) {
        c.steps.push_back(Step{Op::Send, 0, 0, 0, probe_frame(result_.profile, 0x5200 + i)});
        c.steps.push_back(Step{Op::Await, 0, 0, 0, {}});
    }
    ++result_.isolated_runs;
    Execution ex = run_alone(c);
    const std::string stem = rule_stem(ex.verdict.rule);
    if (stem != kRandomDropRule && stem != kRandomCloseRule) {
        bring_back(ex, "");
        return;
    }
    // Known only once its finding is saved, i.e. replayed: a target still busy with what came
    // before (closing the capacity check's thousand connections) may leave one question
    // unanswered without dropping anything at random.
    const Verdict asked = ex.verdict;
    if (!known(asked)) record(c, std::move(ex));
    random_drops_known_ = known(asked) != nullptr;
}

void Campaign::keep(Finding f) {
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
        std::string err;
        if (save_finding(f, dir, err))
            f.folder = dir;
        else
            fmt::print(stderr, "mbstorm fuzz: {}\n", err);
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
                       options_.timeout_ms, deadline_, watch_.get());
    result_.capacity_held = cr.held;
    if (cr.target_down) {
        ++result_.deaths;
        if (cr.verdict && !known(cr.verdict)) keep(capacity_finding(cr));
        recover(cr.verdict ? root_cause_key(cr.verdict) : "");
        return;
    }
    if (watch_) watch_->arm();  // a target at its limit may have closed some of them
    if (!cr.verdict) return;
    // Connections left unserved: the target's own limit, or requests it drops whatever they
    // are? Asked first, and the finding kept only once its flood, replayed, shows it again.
    if (!random_drops_asked_) check_random_drops();
    if (random_drops_known_ || !up_) return;
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
    p.target_up = up_;
    p.restarts = result_.restarts;
    last_progress_ = now;
    last_cases_ = result_.cases;
    on_progress_(p);
}

// Learning the map gets at most a tenth of the run, and never more than this.
constexpr double kLearnBudgetS = 20;

void Campaign::know_the_device() {
    if (!options_.model.empty()) {
        result_.model = options_.model;
    } else if (options_.learn_model && !options_.naive && !result_.profile.serial_line) {
        // Not on a serial line: one request at a time at its baud rate, a sweep would take
        // most of a run (give --map there).
        LearnOptions lo;
        lo.timeout_ms = options_.timeout_ms;
        const double budget_s = options_.max_seconds > 0
                                    ? std::min(options_.max_seconds / 10, kLearnBudgetS)
                                    : kLearnBudgetS;
        lo.budget_ns = static_cast<std::int64_t>(budget_s * 1e9);
        lo.hints = options_.dict_words;
        // A target learning crashed is started again by our command, if we have one.
        if (!options_.restart_cmd.empty()) lo.restart = [this] { return recover(""); };
        // One request at a time on a serial line or RTU/ASCII: a coarser sweep.
        if (result_.profile.framing != codec::Framing::Mbap) lo.stride = 256;
        LearnStats st;
        result_.model = learn_device_model(*options_.connector, result_.profile, lo, &st);
        result_.learn_seconds = st.seconds;
        result_.learn_requests = st.requests;
        learned_killers_ = std::move(st.stream_killers);
    }
    use_probe_inside_the_map();
    if (result_.model.source.empty() || options_.out_dir.empty()) return;
    std::error_code ec;
    std::filesystem::create_directories(options_.out_dir, ec);
    std::ofstream(options_.out_dir + "/model.json") << model_to_json(result_.model);
}

void Campaign::use_probe_inside_the_map() {
    using codec::Table;
    // A learned range's neighbours were each refused alone: the oracle holds reads to that.
    if (result_.model.source == "learned" && !result_.model.partial)
        for (std::size_t t = 0; t < kTableCount; ++t) {
            auto& out = result_.profile.unmapped[t];
            const TableModel& tm = result_.model.tables[t];
            for (const AddressRange& r : tm.ranges) {
                if (r.first > 0 && !tm.contains(r.first - 1u)) out.push_back(r.first - 1);
                if (r.last < 0xFFFF && !tm.contains(r.last + 1u)) out.push_back(r.last + 1);
            }
        }
    for (const Table table :
         {Table::HoldingRegisters, Table::InputRegisters, Table::Coils, Table::DiscreteInputs}) {
        const std::uint8_t fc = codec::function_for(table, codec::RequestShape::AddressQuantity);
        const TableModel& tm = result_.model.table(table);
        if (tm.ranges.empty() || result_.profile.unsupported[fc]) continue;
        const std::uint16_t at = tm.ranges.front().first;
        const Pdu probe = {fc, static_cast<std::uint8_t>(at >> 8), static_cast<std::uint8_t>(at), 0,
                           1};
        if (probe == result_.profile.probe_pdu) return;
        result_.profile.probe_pdu = probe;
        make_batch_runner();  // it probes with the profile's request
        return;
    }
}

void Campaign::arm_watch() {
    // A serial line has one link; a target that serves one connection at a time would be
    // blocked by an idle one.
    if (options_.connector->max_links() <= 1) return;
    watch_ =
        std::make_unique<DeathWatch>(*options_.connector, 3, options_.timeout_ms, &result_.profile);
    const auto answered = [&] {
        return probe_target(*options_.connector, result_.profile, options_.timeout_ms) ==
               ProbeResult::Ok;
    };
    // Twice: a target that drops a request now and then must neither lose its sentinels nor be
    // taken for one that serves one connection at a time over one unanswered probe.
    for (int attempt = 0; attempt < 2; ++attempt) {
        if (!watch_->arm() || !answered()) continue;
        if (!options_.death_watch) {
            watch_.reset();
            return;
        }
        result_.death_watch = true;
        exec_.watch = watch_.get();
        return;
    }
    watch_.reset();
    // Unanswered beside idle connections, answered without them: one connection at a time.
    if (!answered() || !answered()) return;
    result_.profile.one_connection = true;
    make_batch_runner();
}

// Cases that need two connections at once (a second connection, a flood, a concurrent probe)
// show a target that serves one at a time only that: the capacity check reports it once.
bool Campaign::needs_concurrent_connections(const Case& c) const {
    if (!result_.profile.one_connection) return false;
    if (c.connections() > 1) return true;
    return std::any_of(c.steps.begin(), c.steps.end(),
                       [](const Step& s) { return s.op == Op::Flood || s.op == Op::SideProbe; });
}

// No sentinels (a target that serves one connection at a time, a serial line): a register of
// the learned map keeps a value mbstorm wrote; back at its initial value, the process
// restarted.
void Campaign::arm_marker() {
    if (watch_ || !options_.death_watch || result_.model.empty()) return;
    marker_ =
        std::make_unique<StateMarker>(*options_.connector, result_.profile, options_.timeout_ms);
    if (!marker_->arm(result_.model)) {
        marker_.reset();
        return;
    }
    exec_.marker = marker_.get();
    result_.profile.marker_address = marker_->address();
    result_.death_marker = marker_->address();
    result_.death_marker_initial = marker_->initial();
    result_.death_marker_value = marker_->value();
}

// After a pipelined batch broke: the marker back at its initial value, when no case of the
// batch may have written it.
bool Campaign::marker_says_restart(const std::vector<Case>& cases) {
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

// A target that pauses after exceptions spends at most this share of the run in those pauses;
// a request owed such an exception whose kind was sent already goes out one time in this many.
constexpr double kPauseShare = 0.25;
constexpr std::uint64_t kRationedShare = 32;

// What a request owed an exception is, for rationing: its function, why the codec refuses it,
// and which fields are wrong (its address outside the map is a kind of its own).
std::string pausing_kind(const RequestInfo& info, const DeviceModel& m) {
    std::string kind = fmt::format("{:02x}/{}", info.pdu.empty() ? 0 : info.pdu[0],
                                   codec::error_name(info.status.error));
    for (const RequestField f : wrong_fields(info.pdu, m))
        kind += fmt::format("/{}", field_name(f));
    return kind;
}

bool Campaign::rationed(const Case& c) {
    const DeviceModel& m = result_.model;
    // A unit id the device was seen not to answer costs a timeout on a pipelined lane.
    if (!m.units.empty() && m.units.size() < 256) {
        bool silent = false;
        for_each_request(c, result_.profile, [&](const RequestInfo& info) {
            silent =
                std::find(m.units.begin(), m.units.end(), info.header.unit_id) == m.units.end();
            return !silent;
        });
        if (silent && ++rationed_units_seen_ % 16 != 0) return true;
    }
    if (!m.pauses_after_exceptions()) return false;
    unsigned pause_ms = 0;
    std::string kind;
    for_each_request(c, result_.profile, [&](const RequestInfo& info) {
        const std::uint8_t fc = info.pdu.empty() ? 0 : info.pdu[0];
        std::size_t code = static_cast<std::size_t>(info.status.exception);
        if (result_.profile.unsupported[fc]) code = 1;
        if (!owes_exception(info, result_.profile) || code >= m.exception_pause_ms.size() ||
            m.exception_pause_ms[code] == 0)
            return true;
        pause_ms = m.exception_pause_ms[code];
        kind = pausing_kind(info, m);
        return false;
    });
    if (pause_ms == 0) return false;
    // A kind of request not sent yet goes out while the pauses stay within their share of the
    // run; the rest, one in kRationedShare, and only within that share too.
    const double share = kPauseShare * elapsed() * 1000.0;
    const bool affordable = static_cast<double>(pause_spent_ms_) <= share;
    const bool novel = !paused_kinds_.count(kind);
    if (!affordable || (!novel && ++rationed_seen_ % kRationedShare != 0)) return true;
    paused_kinds_.insert(kind);
    pause_spent_ms_ += pause_ms;
    return false;
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
    arm_marker();
    // A known map: stateful cases write inside it, and every read-back in a case run alone
    // is checked (nothing else writes while it runs), unless the user chose the range.
    if (!result_.model.empty() && !options_.state_given) exec_.state = StateRange{0, 0x10000};
    gen_->use_model(&result_.model, exec_.state);
    // What killed the stream while learning, alone, first (at most 8).
    std::vector<Case> killers;
    for (const Pdu& pdu : learned_killers_) {
        if (killers.size() == 8) break;
        Case c;
        c.cls = MutationClass::MapEdge;
        c.function = pdu[0];
        c.steps.push_back(
            Step{Op::Send, 0, 0, 0,
                 frame_of(pdu, 0x0E00, result_.profile.unit, result_.profile.framing)});
        killers.push_back(std::move(c));
    }
    return look_first(std::move(killers), generated);
}

Campaign::Round Campaign::next_round(std::vector<Case>& requeue, std::uint64_t& generated) {
    std::size_t n = lanes_ * lane_depth_;
    if (options_.max_cases) n = std::min<std::uint64_t>(n, options_.max_cases - result_.cases);
    Round r;
    for (Case& c : requeue) {
        // Queued before a crash or hang became known: it may carry that culprit.
        if (would_retrigger(c)) {
            ++result_.skipped_known;
            continue;
        }
        (c.pipelinable ? r.piped : r.alone).push_back(std::move(c));
    }
    requeue.clear();
    if (watch_) watch_->refresh();
    for (std::size_t tries = 0; r.piped.size() + r.alone.size() < n && tries < 8 * n; ++tries) {
        Case c;
        gen_->next(c);
        c.number = ++generated;
        if (would_retrigger(c)) {
            ++result_.skipped_known;
            continue;
        }
        if (rationed(c)) {
            ++result_.rationed;
            continue;
        }
        if (needs_concurrent_connections(c)) {
            ++result_.not_sent_one_connection;
            continue;
        }
        ++r.fresh;
        ++result_.cases_by_class[static_cast<std::size_t>(c.cls)];
        if (options_.coverage) c.pipelinable = false;  // the map is read per case
        (c.pipelinable ? r.piped : r.alone).push_back(std::move(c));
    }
    return r;
}

std::vector<std::string> Campaign::lane_break_keys(const LaneBreak& b) const {
    std::vector<std::string> keys;
    const std::string close = b.closed ? "unexpected-close:" : "hang:";
    if (b.length_mismatch)
        keys.push_back(length_mismatch_close_ == LengthMismatchClose::RefusesTheFrame && b.closed
                           ? fmt::format("unexpected-close:{}", kClosesOnInvalidRequestRule)
                           : fmt::format("stream:{}", kStreamLostRule));
    if (b.closed && b.unanswered_invalid)  // the executor's order (executor.cpp)
        keys.push_back(fmt::format("unexpected-close:{}", kClosesOnInvalidRequestRule));
    if (b.has_previous && b.previous_exception)
        keys.push_back(close + after_exception_rule(b.closed));
    if (b.has_previous) keys.push_back(close + after_request_rule(b.closed, b.previous_culprit));
    keys.push_back(close + unanswered_rule(b.closed, b.unanswered_culprit));
    return keys;
}

std::vector<std::size_t> Campaign::triage(const BatchResult& br, const std::vector<Case>& piped) {
    std::vector<std::size_t> suspects = br.suspects;
    for (const auto& [ci, v] : br.verdicts) {
        if (Finding* f = known(v))
            hit(*f, v, piped[ci]);
        else
            suspects.push_back(ci);
    }
    // A broken lane whose break matches a known root cause needs no re-run.
    for (const LaneBreak& b : br.breaks) {
        for (const std::string& k : lane_break_keys(b)) {
            const auto it = by_key_.find(k);
            if (it == by_key_.end()) continue;
            Finding& f = result_.findings[it->second];
            const std::size_t ci = b.has_previous ? b.previous_case : b.unanswered_case;
            if (ci < piped.size()) hit(f, f.verdict, piped[ci]);
            std::erase(suspects, b.previous_case);
            std::erase(suspects, b.unanswered_case);
            break;
        }
    }
    std::sort(suspects.begin(), suspects.end());
    suspects.erase(std::unique(suspects.begin(), suspects.end()), suspects.end());
    return suspects;
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
        (watch_ && watch_->died(broke ? 200 : 0)) || (broke && marker_says_restart(piped));
    if (!broke && !watched_death) return after;
    batch_->close_all();
    const ProbeResult pr =
        watched_death ? ProbeResult::Closed
                      : probe_target(*options_.connector, result_.profile, options_.timeout_ms);
    if (pr == ProbeResult::ConnectFailed || pr == ProbeResult::Closed) {
        after.whole_target = after.died = true;
        ++result_.deaths;
        if (!recover("")) {
            // Nothing can be re-run: the batch is all there is to show for it.
            if (br.lane_lost) record_lost_batch(piped);
            after.lost = true;
        }
    } else if (pr != ProbeResult::Ok) {
        after.whole_target = true;
        after.lost = !settle();  // hung and never back: the suspects cannot be judged
        after.settled_by_restart = settle_restarted_;
    }
    return after;
}

// The target died or hung as a whole: the culprit may be any unanswered frame (a server may
// not even have answered what came before it). Look at them one by one, lane by lane in turn
// from where each broke, until a crash or hang shows up; the rest go into `later`.
std::vector<std::size_t> Campaign::batch_culprit_candidates(
    const BatchResult& br, const std::vector<std::size_t>& suspects, std::size_t cases) const {
    std::vector<std::size_t> candidates;
    std::vector<bool> seen(cases, false);
    for (std::size_t pos = 0;; ++pos) {
        bool any = false;
        for (const LaneBreak& b : br.breaks) {
            if (pos >= b.unanswered.size()) continue;
            any = true;
            const std::size_t ci = b.unanswered[pos];
            if (!seen[ci]) candidates.push_back(ci);
            seen[ci] = true;
        }
        if (!any) break;
    }
    for (std::size_t ci : suspects)
        if (!seen[ci]) candidates.push_back(ci);
    return candidates;
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
        if (found && !charged && (after.died || after.settled_by_restart))
            ++restarts_by_cause_[shown.key];
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
    for (const auto& [key, n] : restarts_by_cause_) {
        const auto it = by_key_.find(key);
        if (it != by_key_.end()) result_.findings[it->second].restarts += n;
    }
    result_.seconds = elapsed();
    progress(true);
    if (options_.start_target) restart_.stop();
}

// --corpus DIR: a new entry is written as it joins (an entry resumed from DIR is there
// already); a write that fails ends the saving, with a note, not the run.
void Campaign::save_to_corpus(const Case& entry) {
    if (options_.corpus_dir.empty() || corpus_write_failed_) return;
    if (resumed_.erase(steps_text(entry))) return;
    std::string error;
    if (!save_corpus_entry(options_.corpus_dir, next_corpus_file_++, entry, error)) {
        corpus_write_failed_ = true;
        result_.corpus_error = error;
    }
}

// --corpus DIR with entries from an earlier run: they run first.
bool Campaign::resume_corpus() {
    if (!options_.coverage || options_.corpus_dir.empty()) return true;
    std::vector<Case> saved;
    if (!load_corpus(options_.corpus_dir, saved, result_.error)) return false;
    next_corpus_file_ = saved.size();
    for (const Case& c : saved) resumed_.insert(steps_text(split_frames(c)));
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
    restart_.own_process_group();
    if (wait_for_target_with(restart_, *options_.connector, any, options_.restart_cmd,
                             options_.restart_wait_ms, options_.timeout_ms, deadline_))
        return true;
    restart_.stop();
    result_.error =
        fmt::format("--target-cmd did not bring up a target that answers at {} within {} ms",
                    options_.connector->describe(), options_.restart_wait_ms);
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
    if (options_.start_target && !start_target()) return result_;
    if (!discover_target(*options_.connector, options_.unit, options_.timeout_ms, result_.profile,
                         result_.error))
        return result_;
    result_.started = true;
    result_.coverage = options_.coverage != nullptr;
    exec_.timeout_ms = options_.timeout_ms;
    exec_.state = options_.state;
    start_generator();
    if (!resume_corpus()) {
        result_.started = false;
        restart_.stop();
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
    }
    finish();
    return result_;
}

// Why discovery found no request to probe with: silence, or answers it cannot use (a device
// answering everything with 04 does answer: say what it said).
std::string no_usable_answer(std::uint8_t unit, const std::vector<Pdu>& probes,
                             const std::vector<Pdu>& answers) {
    std::string said;
    bool any = false;
    for (std::size_t i = 0; i < probes.size(); ++i) {
        const Pdu& a = answers[i];
        any = any || !a.empty();
        std::string what =
            a.empty() ? std::string("no answer")
            : a.size() == 2 && a[0] == (probes[i][0] | codec::kExceptionBit)
                ? fmt::format("exception {:02X} ({})", a[1],
                              codec::exception_name(static_cast<codec::ExceptionCode>(a[1])))
                : fmt::format("{} ({})",
                              a.size() == 1 ? "1 byte" : fmt::format("{} bytes", a.size()),
                              hex(a, 8));
        said += fmt::format("{}0x{:02X}: {}", said.empty() ? "" : ", ", probes[i][0], what);
    }
    if (!any) return fmt::format("the target does not answer unit {} ({})", unit, said);
    return fmt::format(
        "the target answers unit {} but no read with a normal response or exception 02, so "
        "there is nothing to probe it with ({})",
        unit, said);
}

}  // namespace

bool discover_target(Connector& target, std::uint8_t unit, int timeout_ms, TargetProfile& profile,
                     std::string& error) {
    profile = TargetProfile{};
    profile.unit = unit;
    profile.framing = target.framing();
    profile.serial_line = target.serial_line();
    const bool framed = profile.framing != codec::Framing::Mbap;
    // Probe candidates, most common first.
    using codec::FunctionCode;
    std::vector<Pdu> probes;
    for (FunctionCode fc : {FunctionCode::ReadHoldingRegisters, FunctionCode::ReadInputRegisters,
                            FunctionCode::ReadCoils, FunctionCode::ReadDiscreteInputs,
                            FunctionCode::ReportServerId, FunctionCode::Diagnostics})
        probes.push_back(canonical_request(*codec::function_info(codec::to_byte(fc))));
    std::vector<Pdu> frames;
    for (std::size_t i = 0; i < probes.size(); ++i)
        frames.push_back(frame_of(probes[i], static_cast<std::uint16_t>(i), unit, profile.framing));
    bool connected = false;
    auto answers = ask_pipelined(target, frames, timeout_ms, connected);
    if (!connected) {
        // Once more, for the reason (refused, unreachable, timed out): the user has to act on it.
        int why = 0;
        error = target.open(timeout_ms, why) ? std::string("cannot connect to the target")
                                             : fmt::format("cannot connect to the target: {}",
                                                           why ? std::strerror(why) : "timed out");
        return false;
    }
    for (std::size_t i = 0; i < probes.size(); ++i) {
        if (!answers[i].empty() && answers[i][0] == probes[i][0]) {
            profile.probe_pdu = probes[i];
            break;
        }
    }
    // A device whose map does not start at 0 answers every probe above with an exception:
    // 02 (its address check) will do until the model gives a read inside the map.
    for (std::size_t i = 0; i < probes.size() && profile.probe_pdu.empty(); ++i)
        if (answers[i].size() == 2 && answers[i][0] == (probes[i][0] | codec::kExceptionBit) &&
            answers[i][1] == static_cast<std::uint8_t>(codec::ExceptionCode::IllegalDataAddress))
            profile.probe_pdu = probes[i];
    if (profile.probe_pdu.empty()) {
        error = no_usable_answer(unit, probes, answers);
        return false;
    }
    // Does it drop what is pipelined behind a request it answers with an exception? Then
    // everything below goes one request at a time.
    // (RTU and ASCII send one request at a time: nothing is pipelined to be dropped.)
    if (!framed) {
        answers = ask_pipelined(
            target, {frame_of(Pdu{0x41}, 0, unit), frame_of(profile.probe_pdu, 1, unit)},
            timeout_ms, connected);
        profile.drops_after_exception =
            answers[0].size() == 2 && (answers[0][0] & 0x80) && answers[1].empty();
    }
    std::vector<Pdu> pdus = canonical_requests();
    if (framed) {
        // One request at a time: every undefined code asked in turn would cost a timeout each
        // where the target stays silent to them, so they are assumed unsupported.
        pdus.push_back(profile.probe_pdu);
        frames.clear();
        for (std::size_t i = 0; i < pdus.size(); ++i)
            frames.push_back(frame_of(pdus[i], 0, unit, profile.framing));
        answers = ask_pipelined(target, frames, timeout_ms, connected);
    } else if (!profile.drops_after_exception) {
        for (unsigned fc = 0; fc < 256; ++fc)
            if (!codec::is_supported_function(static_cast<std::uint8_t>(fc)))
                pdus.push_back(Pdu{static_cast<std::uint8_t>(fc)});
        pdus.push_back(profile.probe_pdu);
        frames.clear();
        for (std::size_t i = 0; i < pdus.size(); ++i)
            frames.push_back(frame_of(pdus[i], static_cast<std::uint16_t>(i), unit));
        answers = ask_pipelined(target, frames, timeout_ms, connected);
    } else {
        // Undefined codes are assumed unsupported (no vendor extensions learned): asking each
        // would cost the target's pause after every exception.
        pdus.push_back(profile.probe_pdu);
        answers.assign(pdus.size(), {});
        for (std::size_t i = 0; i + 1 < pdus.size(); ++i)
            answers[i] =
                ask_pipelined(target, {frame_of(pdus[i], 0, unit)}, timeout_ms, connected).front();
    }
    // Silence counts only where the stream went on (the probe behind them was answered).
    const bool stream_went_on = profile.drops_after_exception || !answers.back().empty();
    for (std::size_t i = 0; i + 1 < pdus.size(); ++i) {
        const Pdu& a = answers[i];
        if (a.empty()) {
            if (stream_went_on && codec::is_supported_function(pdus[i][0]))
                profile.silent[pdus[i][0]] = true;
            continue;
        }
        const std::uint8_t fc = pdus[i][0];
        if (a.size() == 2 && a[0] == (fc | codec::kExceptionBit) &&
            a[1] == static_cast<std::uint8_t>(codec::ExceptionCode::IllegalFunction))
            profile.unsupported[fc] = true;
        if (!codec::is_supported_function(fc) && a[0] == fc) profile.extended[fc] = true;
    }
    return true;
}

bool wait_for_target_with(RestartCommand& command, Connector& target, const TargetProfile& profile,
                          const std::string& restart_cmd, int wait_ms, int timeout_ms,
                          std::int64_t deadline_ns) {
    const std::int64_t wait_ns = std::int64_t{wait_ms} * net::kNsPerMs;
    std::int64_t deadline = net::now_ns() + wait_ns;
    bool command_running = false, was_running = false;
    if (!restart_cmd.empty()) {
        // One copy at a time: a command still running (a slow restart, or the target itself
        // run in the foreground) is waited for, not started again.
        command_running = was_running = command.running();
        if (!command_running) {
            std::string error;
            command_running = command.start(restart_cmd, error);
            if (!command_running) fmt::print(stderr, "mbstorm fuzz: {}\n", error);
        }
        // The wait counts from when the command returns (a `systemctl restart` may take its
        // time); one that does not return (the target in the foreground) gets a minute more.
        if (command_running) deadline += kRestartCommandGraceNs;
    }
    // A command still running from an earlier restart is the target in the foreground: if it
    // returns now, the target it ran is the one that died (sentinels see a death before the
    // process has quite ended), and it is started again, once.
    bool foreground = was_running;
    int backoff_ms = 20;
    for (;;) {
        if (command_running && command.returned()) {
            command_running = false;
            deadline = net::now_ns() + wait_ns;
            std::string error;
            if (foreground && command.start(restart_cmd, error)) {
                command_running = true;
                deadline += kRestartCommandGraceNs;
            }
            foreground = false;
        }
        if (probe_target(target, profile, std::min(timeout_ms, 1000)) == ProbeResult::Ok)
            return true;
        const std::int64_t now = net::now_ns();
        if (now >= deadline || (deadline_ns && now >= deadline_ns)) return false;
        std::this_thread::sleep_for(std::chrono::milliseconds(backoff_ms));
        backoff_ms = std::min(backoff_ms * 3 / 2, 1000);
    }
}

bool wait_for_target(Connector& target, const TargetProfile& profile,
                     const std::string& restart_cmd, int wait_ms, int timeout_ms,
                     std::int64_t deadline_ns) {
    RestartCommand command;
    return wait_for_target_with(command, target, profile, restart_cmd, wait_ms, timeout_ms,
                                deadline_ns);
}

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
