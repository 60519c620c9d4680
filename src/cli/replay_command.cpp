// `mbstorm replay FINDING --target HOST:PORT`: re-sends a saved finding's case and says whether
// the same oracle still fires. Exit 1: reproduces, 0: does not, 2: usage.
#include <fmt/format.h>

#include <memory>
#include <string>

#include "cli/commands.hpp"
#include "cli/duration_option.hpp"
#include "cli/fuzz_target.hpp"
#include "cli/transport_options.hpp"
#include "netfuzz/campaign.hpp"
#include "netfuzz/death_watch.hpp"
#include "netfuzz/executor.hpp"
#include "netfuzz/finding.hpp"
#include "netfuzz/state_marker.hpp"

namespace mbstorm::cli {
namespace {

struct ReplayOptions {
    std::string finding;
    std::string target;
    bool allow_remote = false;
    std::uint64_t timeout_ns = 0;  // 0: the finding's own timeout
    unsigned runs = 1;
    bool original = false;
    TransportOptions transport;
};

int run_replay(const ReplayOptions& o) {
    const Result<std::shared_ptr<netfuzz::Connector>> connector =
        make_fuzz_connector(o.target, o.allow_remote, o.transport);
    if (!connector.ok()) return fail("replay", connector.error());
    netfuzz::Connector& target = **connector;
    Result<netfuzz::Finding> loaded = netfuzz::load_finding(o.finding);
    if (!loaded.ok()) return fail("replay", loaded.error());
    netfuzz::Finding f = std::move(loaded).value();
    // The case's bytes are framed as the transport it was found over framed them.
    if (f.profile.framing != target.framing() || f.profile.serial_line != target.serial_line()) {
        auto over = [](codec::Framing framing, bool serial) {
            return framing == codec::Framing::Mbap ? std::string(
                                                         "Modbus TCP (MBAP: --transport "
                                                         "tcp or tls)")
                   : serial ? fmt::format("a serial line (--serial DEVICE --framing {})",
                                          codec::framing_name(framing))
                            : std::string("RTU over TCP (--transport rtu-over-tcp)");
        };
        return usage_error(
            "replay", fmt::format("the finding was found over {}; replay it over the same, not "
                                  "over {}",
                                  over(f.profile.framing, f.profile.serial_line),
                                  over(target.framing(), target.serial_line())));
    }
    fmt::print(stderr, "mbstorm replay: WARNING: writes may be sent to {}\n", target.describe());
    fmt::print("finding: {} ({})\n", f.verdict.summary, f.key());
    if (!f.note.empty()) fmt::print("note: {}\n", f.note);
    netfuzz::ExecOptions ex;
    ex.timeout_ms = o.timeout_ns ? static_cast<int>(o.timeout_ns / 1'000'000) : f.timeout_ms;
    ex.state = f.state;
    // Patient with a frame in pieces: the target acts on each before the next goes out, so a
    // finding about how it reassembles frames reproduces on a loaded host too.
    ex.piece_settle_ms = 20;
    // Idle sentinels, as in the run: a crash replays as a crash under a supervisor too.
    netfuzz::DeathWatch watch(target, 3, ex.timeout_ms, &f.profile);
    // A target that serves one connection at a time cannot hold sentinels: the run watched a
    // marker register instead, and so does replay.
    const bool can_watch = target.max_links() > 1 && !f.profile.one_connection;
    netfuzz::StateMarker marker(target, f.profile, ex.timeout_ms);
    const bool use_marker = !can_watch && f.profile.marker_address >= 0;
    unsigned reproduced = 0;
    const netfuzz::Case& replayed = o.original ? f.original_case : f.fuzz_case;
    if (replayed.steps.empty()) {
        return usage_error("replay", "the finding holds no original case");
    }
    for (unsigned i = 0; i < std::max(1u, o.runs); ++i) {
        if (can_watch && !watch.armed()) {
            // A target a supervisor restarts may still be coming back from the last run.
            netfuzz::wait_for_target(target, f.profile, "", 2000, ex.timeout_ms);
            watch.arm();
        }
        ex.watch = watch.armed() ? &watch : nullptr;
        if (use_marker && !marker.armed()) {
            netfuzz::wait_for_target(target, f.profile, "", 2000, ex.timeout_ms);
            marker.arm_at(static_cast<std::uint16_t>(f.profile.marker_address));
        }
        ex.marker = marker.armed() ? &marker : nullptr;
        netfuzz::Execution e = netfuzz::execute_case(replayed, target, f.profile, ex);
        if (e.down_before) {
            // A crash from an earlier run: give the target time to come back.
            if (!netfuzz::wait_for_target(target, f.profile, "", 10000, ex.timeout_ms)) {
                return fail("replay",
                            Error(ErrorCode::Network,
                                  fmt::format("{} does not accept connections{}", target.describe(),
                                              connector_failure(target))));
            }
            e = netfuzz::execute_case(replayed, target, f.profile, ex);
        }
        // As the campaign understood what this target does (e.g. closes on a frame of the
        // wrong length by itself: a refusal, not a lost stream).
        e.verdict = netfuzz::understood_by(f.profile, std::move(e.verdict));
        // The same root cause (oracle and rule); findings saved before rules existed compare
        // by oracle.
        const bool same = f.verdict.rule.empty() ? e.verdict.oracle == f.oracle()
                                                 : netfuzz::same_fault(e.verdict, f.verdict);
        reproduced += same;
        fmt::print("run {}: {}{}\n", i + 1, same ? "REPRODUCES: " : "does not reproduce",
                   e.verdict ? (same ? e.verdict.summary
                                     : " (saw: " + e.verdict.summary + "; root cause " +
                                           netfuzz::root_cause_key(e.verdict) + ")")
                             : std::string());
        if (same)
            fmt::print("  expected: {}\n  seen:     {}\n", e.verdict.expected, e.verdict.seen);

        // Only another run needs the target back.
        if (e.target_down && i + 1 < std::max(1u, o.runs))
            netfuzz::wait_for_target(target, f.profile, "", 10000, ex.timeout_ms);
    }
    fmt::print("{} of {} run(s) reproduced the finding ({})\n", reproduced, std::max(1u, o.runs),
               o.original    ? "the case as first found"
               : f.minimized ? "the minimised case"
                             : "the case as found: it was not minimised");
    return reproduced ? kExitFailed : kExitOk;
}

}  // namespace

void add_replay_command(CLI::App& app, Action& action) {
    auto o = std::make_shared<ReplayOptions>();
    auto* cmd = app.add_subcommand(
        "replay", "Re-send a saved fuzz finding and say whether it still reproduces");
    cmd->add_option("finding", o->finding, "finding folder (or its finding.json)")->required();
    cmd->add_option("--target", o->target,
                    "server to replay against: HOST[:PORT], [IPv6]:PORT or an IPv6 "
                    "address, port 502 if omitted (802 with --transport tls; required but with "
                    "--serial)");
    cmd->add_flag("--allow-remote", o->allow_remote, "allow a target outside 127.0.0.0/8 and ::1");
    add_duration_option(cmd, "--timeout", o->timeout_ns, "answer timeout (default: the finding's)");
    cmd->add_option("--runs", o->runs, "replay this many times and report k of n")
        ->check(CLI::Range(1u, 1000u));
    cmd->add_flag("--original", o->original,
                  "replay the case as it was first found, not the minimised one");
    add_transport_options(cmd, o->transport, TransportSide::Client);
    cmd->callback([o, &action] {
        action = [o] {
            if (const Error e = check_transport(o->transport, "replay"); !e.ok())
                return fail("replay", e);
            if (o->target.empty() && o->transport.kind() != TransportKind::Serial)
                return usage_error("replay", "--target is required");
            return run_replay(*o);
        };
    });
}

}  // namespace mbstorm::cli
