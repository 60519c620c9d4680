#include "netfuzz/campaign.hpp"

#include <fmt/format.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <set>
#include <thread>
#include <utility>

#include "codec/function_code.hpp"
#include "codec/limits.hpp"
#include "net/clock.hpp"
#include "netfuzz/batch.hpp"
#include "netfuzz/generator.hpp"
#include "netfuzz/minimize.hpp"
#include "netfuzz/restart_command.hpp"

namespace mbstorm::netfuzz {
namespace {

namespace lim = codec::limits;
using Pdu = std::vector<std::uint8_t>;

// How much longer than --restart-wait a --restart-cmd that has not returned may take.
constexpr std::int64_t kRestartCommandGraceNs = 60 * net::kNsPerSec;

// How big a reproducer is: its steps first, then its bytes.
std::pair<std::size_t, std::size_t> size_of(const Case& c) {
    std::size_t bytes = 0;
    for (const Step& s : c.steps) bytes += s.bytes.size();
    return {c.steps.size(), bytes};
}

Pdu frame_of(const Pdu& pdu, std::uint16_t tid, std::uint8_t unit) {
    Pdu f(lim::kMbapHeader + pdu.size());
    codec::store_be16(f.data(), tid);
    codec::store_be16(f.data() + 2, 0);
    codec::store_be16(f.data() + 4, static_cast<std::uint16_t>(pdu.size() + 1));
    f[6] = unit;
    std::copy(pdu.begin(), pdu.end(), f.begin() + lim::kMbapHeader);
    return f;
}

// Sends all frames at once on one connection and collects answers by transaction id until
// the last one is answered, the connection closes or the time is up.
std::vector<Pdu> pipeline(const net::Endpoint& target, const std::vector<Pdu>& frames,
                          int timeout_ms, bool& connected) {
    std::vector<Pdu> answers(frames.size());
    const int raw = connect_with_timeout(target, timeout_ms);
    connected = raw >= 0;
    if (raw < 0) return answers;
    net::UniqueFd fd(raw);
    Pdu out;
    for (const Pdu& f : frames) out.insert(out.end(), f.begin(), f.end());
    std::size_t sent = 0;
    Pdu in;
    std::size_t pos = 0;
    const std::int64_t deadline = net::now_ns() + timeout_ms * net::kNsPerMs;
    while (net::now_ns() < deadline && answers.back().empty()) {
        pollfd p{fd.get(), static_cast<short>(POLLIN | (sent < out.size() ? POLLOUT : 0)), 0};
        if (::poll(&p, 1, 20) <= 0) continue;
        if (p.revents & POLLOUT) {
            const ssize_t n = ::send(fd.get(), out.data() + sent, out.size() - sent, MSG_NOSIGNAL);
            if (n > 0) sent += static_cast<std::size_t>(n);
        }
        if (p.revents & (POLLIN | POLLHUP | POLLERR)) {
            std::uint8_t buf[8192];
            const ssize_t n = ::recv(fd.get(), buf, sizeof buf, 0);
            if (n <= 0 && !(n < 0 && (errno == EAGAIN || errno == EINTR))) break;
            if (n > 0) in.insert(in.end(), buf, buf + n);
            while (in.size() - pos >= lim::kMbapHeader) {
                const auto h = codec::read_mbap_header(in.data() + pos);
                if (h.length < 2 || h.length > lim::kMaxMbapLength) return answers;
                if (in.size() - pos < 6u + h.length) break;
                if (h.transaction_id < answers.size())
                    answers[h.transaction_id].assign(
                        in.begin() + static_cast<std::ptrdiff_t>(pos + 7),
                        in.begin() + static_cast<std::ptrdiff_t>(pos + 6 + h.length));
                pos += 6u + h.length;
            }
        }
    }
    return answers;
}

struct Key {
    Oracle oracle;
    std::uint8_t function;
    MutationClass cls;
    bool operator<(const Key& o) const {
        return std::tie(oracle, function, cls) < std::tie(o.oracle, o.function, o.cls);
    }
};

class Campaign {
  public:
    Campaign(const CampaignOptions& o, const ProgressFn& p, const FindingFn& f)
        : o_(o), on_progress_(p), on_finding_(f) {}
    CampaignResult run();

  private:
    bool out_of_budget() const {
        if (o_.stop && o_.stop->load()) return true;
        if (o_.max_cases && r_.cases >= o_.max_cases) return true;
        if (o_.max_seconds > 0 && elapsed() >= o_.max_seconds) return true;
        return false;
    }
    double elapsed() const { return static_cast<double>(net::now_ns() - start_) / 1e9; }
    // Runs one case alone; records a finding when an oracle fires. False: target lost.
    bool isolate(const Case& c, bool& fired);
    bool recover();
    void record(const Case& c, Execution ex);
    // The target went down in a pipelined batch and was lost before the case that did it was
    // re-run alone: keep the batch itself (every frame, in order) as an unconfirmed finding.
    void record_lost_batch(const std::vector<Case>& batch);
    // Numbers, stamps, saves and announces a new finding.
    void keep(Finding f);
    void progress(bool force);

    const CampaignOptions& o_;
    const ProgressFn& on_progress_;
    const FindingFn& on_finding_;
    CampaignResult r_;
    std::int64_t start_ = 0;
    std::set<Key> seen_;
    Generator* gen_ = nullptr;
    ExecOptions exec_;
    std::int64_t last_progress_ = 0;
    std::uint64_t last_cases_ = 0;
    bool up_ = true;
    std::uint64_t downs_seen_ = 0;  // isolated runs after which the target was down
};

bool Campaign::recover() {
    up_ = false;
    progress(true);
    if (!wait_for_target(o_.target, r_.profile, o_.restart_cmd, o_.restart_wait_ms,
                         o_.timeout_ms)) {
        r_.target_lost = true;
        // Name the command and the wait: the user has to fix one of them.
        r_.stop_reason =
            o_.restart_cmd.empty()
                ? fmt::format(
                      "the target did not come back within {} ms (--restart-wait; no "
                      "--restart-cmd given)",
                      o_.restart_wait_ms)
                : fmt::format(
                      "the target did not come back within {} ms (--restart-wait) after "
                      "--restart-cmd '{}'",
                      o_.restart_wait_ms, o_.restart_cmd);
        return false;
    }
    ++r_.restarts;
    up_ = true;
    return true;
}

bool Campaign::isolate(const Case& c, bool& fired) {
    fired = false;
    ++r_.isolated_runs;
    Execution ex = execute_case(c, o_.target, r_.profile, exec_);
    if (ex.down_before) {
        if (!recover()) return false;
        ex = execute_case(c, o_.target, r_.profile, exec_);
        if (ex.down_before) {
            r_.target_lost = true;
            r_.stop_reason = "the target keeps refusing connections";
            return false;
        }
    }
    const bool down = ex.target_down;
    if (down) ++downs_seen_;
    if (ex.verdict) {
        fired = true;
        record(c, std::move(ex));
    }
    if (down && !recover()) return false;
    return true;
}

// The function code of the first request frame a case sends (0 when there is none).
std::uint8_t first_function(const Case& c) {
    for (const Step& s : c.steps)
        if (s.op == Op::Send && s.bytes.size() > lim::kMbapHeader) return s.bytes[lim::kMbapHeader];
    return c.function;
}

void Campaign::record(const Case& c, Execution ex) {
    const Oracle want = ex.verdict.oracle;
    const bool costly = want == Oracle::Crash || want == Oracle::Hang;
    const Case frames = split_frames(c);
    const bool multi_frame = frames.steps.size() > 1 && c.cls != MutationClass::Split &&
                             c.cls != MutationClass::Drip && c.cls != MutationClass::StatefulSame &&
                             c.cls != MutationClass::StatefulCross;
    if (costly) gen_->deprioritise(c.function, c.cls);
    // Several frames: the finding belongs to whichever frame causes it. Already known when any
    // of its frames has a known key; otherwise shrink first, then key by what is left.
    if (multi_frame) {
        for (const Step& s : frames.steps) {
            if (s.op != Op::Send || s.bytes.size() <= lim::kMbapHeader) continue;
            if (seen_.count(Key{want, s.bytes[lim::kMbapHeader], c.cls})) {
                ++r_.duplicates;
                return;
            }
        }
    } else if (seen_.count(Key{want, c.function, c.cls})) {
        ++r_.duplicates;
        return;
    }
    Finding f;
    f.found_after_s = elapsed();  // when it was seen, not when minimising it ended
    f.verdict = ex.verdict;
    f.fuzz_case = c;
    f.trace = std::move(ex.trace);
    f.original_steps = c.steps.size();
    if (o_.minimize) {
        Execution last;
        bool lost = false;
        auto reproduces = [&](const Case& candidate) {
            if (lost) return false;
            Execution e = execute_case(candidate, o_.target, r_.profile, exec_);
            if (e.down_before || e.target_down) {
                if (!recover()) lost = true;
            }
            if (e.verdict.oracle != want) return false;
            last = std::move(e);
            return true;
        };
        // Crashes and hangs cost a restart or a timeout per try: a smaller budget.
        Case small =
            minimize_case(c, reproduces, costly ? o_.minimize_budget / 3 : o_.minimize_budget);
        if (size_of(small) < size_of(frames) && last.verdict) {
            f.fuzz_case = std::move(small);
            f.verdict = last.verdict;
            f.trace = std::move(last.trace);
            f.minimized = true;
        }
    }
    if (multi_frame) f.fuzz_case.function = first_function(f.fuzz_case);
    if (!seen_.insert(Key{want, f.fuzz_case.function, f.fuzz_case.cls}).second) {
        ++r_.duplicates;
        return;
    }
    if (costly) gen_->deprioritise(f.fuzz_case.function, f.fuzz_case.cls);
    keep(std::move(f));
}

void Campaign::keep(Finding f) {
    f.id = r_.findings.size() + 1;
    f.profile = r_.profile;
    f.target = o_.target_text;
    f.seed = o_.seed;
    f.case_number = r_.cases;
    f.timeout_ms = o_.timeout_ms;
    if (!o_.out_dir.empty()) {
        const std::string dir =
            fmt::format("{}/{:03}-{}-fc{:02X}-{}", o_.out_dir, f.id, oracle_name(f.oracle()),
                        f.fuzz_case.function, class_name(f.fuzz_case.cls));
        std::string err;
        if (save_finding(f, dir, err))
            f.folder = dir;
        else
            fmt::print(stderr, "mbstorm fuzz: {}\n", err);
    }
    r_.findings.push_back(std::move(f));
    if (on_finding_) on_finding_(r_.findings.back());
}

void Campaign::record_lost_batch(const std::vector<Case>& batch) {
    // What the server looks like now decides crash or whole-server hang, as after one case.
    Verdict v = fresh_probe_verdict(probe_target(o_.target, r_.profile, o_.timeout_ms));
    if (!v) v = fresh_probe_verdict(ProbeResult::ConnectFailed);
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
    f.found_after_s = elapsed();      // when it was seen, not when minimising it ended
    f.fuzz_case = split_frames(all);  // one step per frame, the batch's order kept
    f.fuzz_case.function = first_function(f.fuzz_case);
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
    seen_.insert(Key{f.oracle(), f.fuzz_case.function, f.fuzz_case.cls});
    keep(std::move(f));
}

void Campaign::progress(bool force) {
    if (!on_progress_) return;
    const std::int64_t now = net::now_ns();
    const double dt = static_cast<double>(now - last_progress_) / 1e9;
    if (!force && dt < o_.progress_interval_s) return;
    Progress p;
    p.cases = r_.cases;
    p.seconds = elapsed();
    p.cases_per_second = dt > 0 ? static_cast<double>(r_.cases - last_cases_) / dt : 0;
    p.findings = r_.findings.size();
    p.target_up = up_;
    p.restarts = r_.restarts;
    last_progress_ = now;
    last_cases_ = r_.cases;
    on_progress_(p);
}

CampaignResult Campaign::run() {
    start_ = net::now_ns();
    last_progress_ = start_;
    if (!discover_target(o_.target, o_.unit, o_.timeout_ms, r_.profile, r_.error)) return r_;
    r_.started = true;
    exec_.timeout_ms = o_.timeout_ms;
    exec_.settle_ms = std::min(o_.timeout_ms, 300);
    GeneratorOptions go;
    go.seed = o_.seed;
    go.unit = o_.unit;
    go.naive = o_.naive;
    go.isolated_per_mille = o_.isolated_per_mille;
    Generator gen(go);
    gen_ = &gen;
    BatchRunner batch(o_.target, r_.profile, BatchOptions{o_.lanes, o_.timeout_ms});
    const std::size_t round = std::max(1u, o_.lanes) * std::max(1u, o_.lane_depth);
    std::vector<Case> cases(round), piped, alone;
    while (!out_of_budget()) {
        std::size_t n = round;
        if (o_.max_cases) n = std::min<std::uint64_t>(n, o_.max_cases - r_.cases);
        piped.clear();
        alone.clear();
        for (std::size_t i = 0; i < n; ++i) {
            gen.next(cases[i]);
            ++r_.cases_by_class[static_cast<std::size_t>(cases[i].cls)];
            (cases[i].pipelinable ? piped : alone).push_back(cases[i]);
        }
        const std::int64_t t0 = net::now_ns();
        BatchResult br = batch.run(piped);
        const std::int64_t t1 = net::now_ns();
        r_.batch_seconds += static_cast<double>(t1 - t0) / 1e9;
        r_.batched_cases += piped.size();
        if (br.connect_failed || br.lane_lost) {
            batch.close_all();
            if (probe_target(o_.target, r_.profile, o_.timeout_ms) != ProbeResult::Ok &&
                !recover()) {
                // Nothing can be re-run: the batch is all there is to show for it.
                if (br.lane_lost) record_lost_batch(piped);
                r_.cases += n;
                break;
            }
        }
        // The mutation corpus is the valid traffic the generator itself recorded, not what the
        // target answered: answers depend on state that concurrent lanes change in a timing-
        // dependent order, and a seed must replay the same cases.
        bool lost = false;
        const std::uint64_t downs_before = downs_seen_;
        for (std::size_t i : br.suspects) {
            bool fired = false;
            if (!isolate(piped[i], fired)) {
                lost = true;
                break;
            }
            if (!fired) ++r_.unconfirmed;
        }
        // Lost while re-running suspects and none of them was seen taking the target down:
        // what did it is still somewhere in the batch.
        if (lost && downs_seen_ == downs_before) record_lost_batch(piped);
        for (std::size_t i = 0; !lost && i < alone.size(); ++i) {
            bool fired = false;
            if (!isolate(alone[i], fired)) lost = true;
        }
        r_.isolated_seconds += static_cast<double>(net::now_ns() - t1) / 1e9;
        r_.cases += n;
        progress(false);
        if (lost) break;
    }
    if (r_.stop_reason.empty()) {
        r_.stop_reason = (o_.stop && o_.stop->load())                 ? "interrupted"
                         : (o_.max_cases && r_.cases >= o_.max_cases) ? "case limit reached"
                                                                      : "time limit reached";
    }
    r_.seconds = elapsed();
    progress(true);
    return r_;
}

}  // namespace

bool discover_target(const net::Endpoint& target, std::uint8_t unit, int timeout_ms,
                     TargetProfile& profile, std::string& error) {
    profile = TargetProfile{};
    profile.unit = unit;
    // Probe candidates, most common first.
    const std::vector<Pdu> probes = {
        {0x03, 0, 0, 0, 1},      {0x04, 0, 0, 0, 1}, {0x01, 0, 0, 0, 1}, {0x02, 0, 0, 0, 1}, {0x11},
        {0x08, 0, 0, 0x12, 0x34}};
    std::vector<Pdu> frames;
    for (std::size_t i = 0; i < probes.size(); ++i)
        frames.push_back(frame_of(probes[i], static_cast<std::uint16_t>(i), unit));
    bool connected = false;
    auto answers = pipeline(target, frames, timeout_ms, connected);
    if (!connected) {
        error = "cannot connect to the target";
        return false;
    }
    for (std::size_t i = 0; i < probes.size(); ++i) {
        if (!answers[i].empty() && answers[i][0] == probes[i][0]) {
            profile.probe_pdu = probes[i];
            break;
        }
    }
    if (profile.probe_pdu.empty()) {
        error = fmt::format("the target does not answer unit {} (tried FC 03, 04, 01, 02, 11, 08)",
                            unit);
        return false;
    }
    // Canonical valid requests of every function code the codec knows, and every other code
    // bare; the probe last as a fence.
    const std::vector<Pdu> canonical = {{0x01, 0, 0, 0, 1},
                                        {0x02, 0, 0, 0, 1},
                                        {0x03, 0, 0, 0, 1},
                                        {0x04, 0, 0, 0, 1},
                                        {0x05, 0x5F, 0xFF, 0xFF, 0x00},
                                        {0x06, 0x5F, 0xFF, 0, 0},
                                        {0x07},
                                        {0x08, 0, 0, 0x12, 0x34},
                                        {0x0B},
                                        {0x0C},
                                        {0x0F, 0x5F, 0xFF, 0, 1, 1, 0},
                                        {0x10, 0x5F, 0xFF, 0, 1, 2, 0, 0},
                                        {0x11},
                                        {0x14, 7, 6, 0, 1, 0, 0, 0, 1},
                                        {0x15, 9, 6, 0, 1, 0, 0, 0, 1, 0, 0},
                                        {0x16, 0x5F, 0xFF, 0xFF, 0xFF, 0, 0},
                                        {0x17, 0, 0, 0, 1, 0x5F, 0xFF, 0, 1, 2, 0, 0},
                                        {0x18, 0x5F, 0xFF},
                                        {0x2B, 0x0E, 0x01, 0x00}};
    std::vector<Pdu> pdus = canonical;
    for (unsigned fc = 0; fc < 256; ++fc)
        if (!codec::is_supported_function(static_cast<std::uint8_t>(fc)))
            pdus.push_back(Pdu{static_cast<std::uint8_t>(fc)});
    pdus.push_back(profile.probe_pdu);
    frames.clear();
    for (std::size_t i = 0; i < pdus.size(); ++i)
        frames.push_back(frame_of(pdus[i], static_cast<std::uint16_t>(i), unit));
    answers = pipeline(target, frames, timeout_ms, connected);
    for (std::size_t i = 0; i + 1 < pdus.size(); ++i) {
        const Pdu& a = answers[i];
        if (a.empty()) continue;
        const std::uint8_t fc = pdus[i][0];
        if (a.size() == 2 && a[0] == (fc | 0x80) && a[1] == 0x01) profile.unsupported[fc] = true;
        if (!codec::is_supported_function(fc) && a[0] == fc) profile.extended[fc] = true;
    }
    return true;
}

bool wait_for_target(const net::Endpoint& target, const TargetProfile& profile,
                     const std::string& restart_cmd, int wait_ms, int timeout_ms) {
    const std::int64_t wait_ns = std::int64_t{wait_ms} * net::kNsPerMs;
    std::int64_t deadline = net::now_ns() + wait_ns;
    RestartCommand command;
    bool command_running = false;
    if (!restart_cmd.empty()) {
        std::string error;
        command_running = command.start(restart_cmd, error);
        // The wait counts from when the command returns (a `systemctl restart` may take its
        // time); one that does not return (the target in the foreground) gets a minute more.
        if (command_running) deadline += kRestartCommandGraceNs;
    }
    int backoff_ms = 20;
    for (;;) {
        if (command_running && command.returned()) {
            command_running = false;
            deadline = net::now_ns() + wait_ns;
        }
        if (probe_target(target, profile, std::min(timeout_ms, 1000)) == ProbeResult::Ok)
            return true;
        if (net::now_ns() >= deadline) return false;
        std::this_thread::sleep_for(std::chrono::milliseconds(backoff_ms));
        backoff_ms = std::min(backoff_ms * 3 / 2, 1000);
    }
}

CampaignResult run_campaign(const CampaignOptions& options, const ProgressFn& on_progress,
                            const FindingFn& on_finding) {
    Campaign c(options, on_progress, on_finding);
    return c.run();
}

}  // namespace mbstorm::netfuzz
