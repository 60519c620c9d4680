// `mbstorm fuzz`: the structure-aware network fuzzer (src/netfuzz). Exit 1 with findings,
// 0 when clean, 2 for usage errors or an unreachable target.
#include <fmt/format.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <thread>
#include <utility>

#include "cli/commands.hpp"
#include "cli/deprecated_option.hpp"
#include "cli/duration_option.hpp"
#include "cli/fuzz_target.hpp"
#include "cli/transport_options.hpp"
#include "codec/function_code.hpp"
#include "netfuzz/baseline.hpp"
#include "netfuzz/campaign.hpp"
#include "netfuzz/coverage_report.hpp"
#include "netfuzz/device_model.hpp"
#include "netfuzz/dictionary.hpp"
#include "netfuzz/outputs.hpp"
#include "report/files.hpp"

namespace mbstorm::cli {
namespace {

std::atomic<bool> g_stop{false};
std::atomic<int> g_stop_signal{0};  // which signal stopped the campaign
void on_fuzz_stop_signal(int signal_number) {
    g_stop_signal.store(signal_number);
    g_stop.store(true);
}

struct FuzzOptions {
    std::string target;
    bool allow_remote = false;
    int unit = 1;
    std::uint64_t seed = 1;
    std::uint64_t duration_ns = 0;
    std::uint64_t cases = 0;
    std::uint64_t max_findings = 0;  // 0: no limit
    std::uint64_t timeout_ns = 1'000'000'000;
    unsigned lanes = 4;
    unsigned isolated_per_mille = 10;
    std::string out_dir = "mbstorm-findings";
    std::string baseline;                  // --baseline: an earlier run's --json or --sarif file
    std::uint64_t wait_for_target_ns = 0;  // --wait-for-target: retry the first connect
    std::string restart_cmd;
    std::uint64_t restart_wait_ns = 15'000'000'000;
    std::string json, junit, sarif, html;
    bool no_minimize = false;
    bool naive = false;
    bool quiet = false;
    std::string dict;
    std::string state_range = "0x6000-0x6FFF";
    bool state_given = false;
    std::string map, model;
    bool no_model = false;
    std::uint32_t max_connections = 4096;
    TransportOptions transport;
    std::string target_cmd;
    bool coverage = false;
    std::uint64_t coverage_map_size = 65536;
    std::string corpus_dir;
    std::string coverage_report;
};

// "all", or A-B (decimal or 0x hex, inclusive) for --state-range.
Result<netfuzz::StateRange> parse_state_range(const std::string& text) {
    if (text == "all") return netfuzz::StateRange{0, 0x10000};
    const auto dash = text.find('-');
    auto number = [](const std::string& s, unsigned long& v) {
        try {
            std::size_t used = 0;
            v = std::stoul(s, &used, 0);
            return used == s.size() && v <= 0xFFFF;
        } catch (const std::exception&) {
            return false;
        }
    };
    unsigned long a = 0, b = 0;
    if (dash == std::string::npos || !number(text.substr(0, dash), a) ||
        !number(text.substr(dash + 1), b) || b < a || b - a < 255) {
        return Error(ErrorCode::InvalidInput,
                     fmt::format("--state-range '{}': expected 'all' or FIRST-LAST (protocol "
                                 "addresses 0..65535, at least 256 of them, e.g. 0x6000-0x6FFF)",
                                 text));
    }
    return netfuzz::StateRange{static_cast<std::uint16_t>(a),
                               static_cast<std::uint32_t>(b - a + 1)};
}

// "0x05 0x06 0x08 ...": the codes the codec says change a device, all of which the fuzzer sends.
std::string write_function_codes() {
    std::string codes;
    for (const codec::FunctionInfo& f : codec::public_functions())
        if (f.writes)
            codes += fmt::format("{}0x{:02X}", codes.empty() ? "" : " ", codec::to_byte(f.code));
    return codes;
}

bool write_output(const std::string& path, const std::string& text) {
    const Error error = report::write_text_file(path, text);
    if (error.ok()) return true;
    fmt::print(stderr, "mbstorm fuzz: {}\n", error.text());
    return false;
}

// --coverage-report: the functions the target listed whose entry no case reached.
bool write_coverage_report(const std::string& path, const netfuzz::FunctionListFile& functions,
                           const netfuzz::CoverageMap& map) {
    Result<std::string> list = functions.read();
    Result<std::string> made = list.ok() ? netfuzz::coverage_report(*list, map) : list;
    if (!made.ok()) {
        // Reported, not fatal: the campaign's own results are written all the same.
        fmt::print(stderr, "mbstorm fuzz: --coverage-report: {}\n", made.error().text());
        return false;
    }
    const std::string& report = *made;
    fmt::print(stderr, "mbstorm fuzz: --coverage-report {}: {}", path == "-" ? "(stdout)" : path,
               report.substr(0, report.find('\n') + 1));
    return write_output(path, report);
}

// --target-cmd and --coverage: mbstorm starts (and restarts) the target, handing it the map
// and, for --coverage-report, the file it lists its functions in (`functions`).
Error set_up_target_command(const FuzzOptions& o, netfuzz::CampaignOptions& c,
                            std::unique_ptr<netfuzz::FunctionListFile>& functions) {
    auto refused = [](const char* why) { return Error(ErrorCode::InvalidInput, why); };
    if (!o.target_cmd.empty() && !o.restart_cmd.empty())
        return refused("--target-cmd starts and restarts the target: --restart-cmd is not needed");
    if (o.coverage && o.target_cmd.empty())
        return refused("--coverage needs --target-cmd (mbstorm hands the target its coverage map)");
    if (!o.corpus_dir.empty() && !o.coverage)
        return refused("--corpus keeps a coverage corpus: it needs --coverage");
    if (!o.coverage_report.empty() && !o.coverage)
        return refused(
            "--coverage-report lists the functions no case reached: it needs --coverage");
    c.corpus_dir = o.corpus_dir;
    if (o.target_cmd.empty()) return Error::none();
    c.restart_cmd = o.target_cmd;
    c.start_target = true;
    if (!o.coverage) return Error::none();
    c.coverage = std::make_shared<netfuzz::CoverageMap>();
    if (Error e = c.coverage->create(o.coverage_map_size); !e.ok()) return e;
    c.coverage->export_environment();
    if (o.coverage_report.empty()) return Error::none();
    functions = std::make_unique<netfuzz::FunctionListFile>();
    if (Error e = functions->create(); !e.ok()) return e;
    functions->export_environment();
    return Error::none();
}

// --wait-for-target: a target started just before mbstorm (a CI service, a container) may not
// accept connections yet. Retries the connect every 100 ms; false when the time ran out.
bool wait_for_target(netfuzz::Connector& target, std::uint64_t wait_ns, int& error) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::nanoseconds(wait_ns);
    fmt::print(stderr, "mbstorm fuzz: waiting up to {:.1f} s for {} to accept a connection\n",
               static_cast<double>(wait_ns) / 1e9, target.describe());
    for (;;) {
        if (target.open(1000, error)) return true;
        if (g_stop.load() || std::chrono::steady_clock::now() >= until) return false;
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
}

// Findings whose root cause --baseline lists are known: reported, not failing the run.
int fuzz_exit_code(const netfuzz::CampaignResult& r) {
    return r.new_findings() == 0 && !r.target_lost ? kExitOk : kExitFailed;
}

// What the user hands the campaign besides flags: the state range, a device map or model,
// a dictionary. An Error naming the bad one.
Error read_fuzz_inputs(const FuzzOptions& o, netfuzz::CampaignOptions& c) {
    Result<netfuzz::StateRange> state = parse_state_range(o.state_range);
    if (!state.ok()) return std::move(state).error();
    c.state = *state;
    c.state_given = o.state_given;
    if (!o.map.empty() + !o.model.empty() + o.no_model > 1)
        return Error(ErrorCode::InvalidInput,
                     "--map, --device-model and --no-model exclude each other");
    if (!o.map.empty() || !o.model.empty()) {
        Result<netfuzz::DeviceModel> model =
            o.map.empty() ? netfuzz::load_model(o.model) : netfuzz::parse_map(o.map);
        if (!model.ok()) return std::move(model).error();
        c.model = std::move(model).value();
    }
    c.learn_model = !o.no_model;
    if (!o.dict.empty()) {
        Result<netfuzz::Dictionary> d = netfuzz::load_dictionary(o.dict);
        if (!d.ok()) return std::move(d).error();
        c.dict_words = std::move(d->words);
        c.dict_tokens = std::move(d->tokens);
    }
    c.max_connections = o.max_connections;
    return Error::none();
}

// Report paths are checked before the run: a summary that cannot be written must not cost a
// whole campaign first. "" or the problem.
std::string check_fuzz_outputs(const FuzzOptions& o) {
    for (const auto& [flag, path] : {std::pair<const char*, const std::string&>{"--json", o.json},
                                     {"--junit", o.junit},
                                     {"--sarif", o.sarif},
                                     {"--html", o.html},
                                     {"--coverage-report", o.coverage_report}}) {
        if (!path.empty() && path != "-")
            if (Error bad = report::check_writable(path); !bad.ok())
                return fmt::format("cannot write {} {}", flag, bad.text());
    }
    const int on_stdout = (o.json == "-") + (o.junit == "-") + (o.sarif == "-") + (o.html == "-") +
                          (o.coverage_report == "-");
    if (on_stdout > 1)
        return "only one of --json, --junit, --sarif, --html and --coverage-report can be '-' "
               "(stdout)";
    return {};
}

int run_fuzz(const FuzzOptions& o) {
    netfuzz::CampaignOptions c;
    Result<std::shared_ptr<netfuzz::Connector>> connector =
        make_fuzz_connector(o.target, o.allow_remote, o.transport);
    if (!connector.ok()) return fail("fuzz", connector.error());
    c.connector = std::move(connector).value();
    if (o.duration_ns == 0 && o.cases == 0)
        return usage_error("fuzz", "bound the run with --seconds DURATION or --cases N");
    if (Error e = read_fuzz_inputs(o, c); !e.ok()) return fail("fuzz", e);
    netfuzz::Baseline baseline;
    if (!o.baseline.empty()) {
        Result<netfuzz::Baseline> loaded = netfuzz::load_baseline(o.baseline);
        if (!loaded.ok()) return fail("fuzz", loaded.error());
        baseline = std::move(loaded).value();
    }
    if (std::string e = check_fuzz_outputs(o); !e.empty()) return usage_error("fuzz", e);
    const bool on_stdout = o.json == "-" || o.junit == "-" || o.sarif == "-" || o.html == "-" ||
                           o.coverage_report == "-";
    // The first line, always: this is not a read-only tool.
    fmt::print(stderr,
               "mbstorm fuzz: WARNING: writes will be sent to {} (function codes {} and malformed "
               "frames); only fuzz devices you may change\n",
               c.connector->describe(), write_function_codes());
    c.target_text = c.connector->describe();
    c.unit = static_cast<std::uint8_t>(o.unit);
    c.seed = o.seed;
    c.max_cases = o.cases;
    c.max_seconds = static_cast<double>(o.duration_ns) / 1e9;
    c.max_findings = static_cast<std::size_t>(o.max_findings);
    c.timeout_ms = static_cast<int>(std::max<std::uint64_t>(o.timeout_ns / 1'000'000, 1));
    c.lanes = o.lanes;
    c.isolated_per_mille = o.isolated_per_mille;
    c.naive = o.naive;
    c.minimize = !o.no_minimize;
    c.restart_cmd = o.restart_cmd;
    c.restart_wait_ms = static_cast<int>(o.restart_wait_ns / 1'000'000);
    std::unique_ptr<netfuzz::FunctionListFile> functions;
    if (Error e = set_up_target_command(o, c, functions); !e.ok()) return fail("fuzz", e);
    c.out_dir = o.out_dir;
    c.stop = &g_stop;
    std::signal(SIGINT, on_fuzz_stop_signal);
    std::signal(SIGTERM, on_fuzz_stop_signal);

    if (int err = 0;
        o.wait_for_target_ns && !wait_for_target(*c.connector, o.wait_for_target_ns, err)) {
        fmt::print(stderr,
                   "mbstorm fuzz: {} did not accept a connection within {:.1f} s "
                   "(--wait-for-target): {}\n",
                   c.target_text, static_cast<double>(o.wait_for_target_ns) / 1e9,
                   err ? std::strerror(err) : "stopped");
        return kExitUsage;
    }
    const bool quiet = o.quiet;
    auto progress = [quiet](const netfuzz::Progress& p) {
        if (quiet) return;
        fmt::print(stderr, "[{:7.1f}s] {} cases, {:.0f} cases/s, {} finding(s), target {}{}\n",
                   p.seconds, p.cases, p.cases_per_second, p.findings,
                   p.target_up ? "up" : "DOWN (waiting)",
                   p.restarts ? fmt::format(", {} restart(s)", p.restarts) : std::string());
    };
    auto finding = [](const netfuzz::Finding& f) {
        fmt::print(stderr, "FINDING #{} {}: {}\n", f.id, netfuzz::oracle_name(f.oracle()),
                   f.verdict.summary);
        if (!f.folder.empty()) fmt::print(stderr, "  saved to {}\n", f.folder);
    };
    netfuzz::CampaignResult r = netfuzz::run_campaign(c, progress, finding);
    std::signal(SIGINT, SIG_DFL);
    std::signal(SIGTERM, SIG_DFL);
    // Every report names the signal, not only the last stderr line.
    if (const int sig = g_stop_signal.load(); sig != 0 && r.stop_reason == "interrupted")
        r.stop_reason = fmt::format("interrupted by {}", signal_name(sig));
    if (!r.started) {
        Error error = std::move(r.error);
        error.prefixed(c.target_text);
        // What the connector knows (a TLS handshake's refusal) ends the message.
        return fail("fuzz", Error(error.code(), error.message() + connector_failure(*c.connector),
                                  error.place()));
    }
    if (!o.baseline.empty()) netfuzz::apply_baseline(baseline, r);
    const netfuzz::RunInfo info{c.target_text, o.seed, o.naive};
    // The summary is the result: stdout, unless a report file takes stdout.
    fmt::print(on_stdout ? stderr : stdout, "{}", netfuzz::format_fuzz_summary(r, info));
    std::fflush(on_stdout ? stderr : stdout);
    bool ok = true;
    if (!o.json.empty()) ok &= write_output(o.json, netfuzz::format_fuzz_json(r, info));
    if (!o.junit.empty()) ok &= write_output(o.junit, netfuzz::format_fuzz_junit(r, info));
    if (!o.sarif.empty()) ok &= write_output(o.sarif, netfuzz::format_fuzz_sarif(r, info));
    if (!o.html.empty()) ok &= write_output(o.html, netfuzz::format_fuzz_html(r, info));
    if (functions) ok &= write_coverage_report(o.coverage_report, *functions, *c.coverage);
    if (!ok) return kExitUsage;
    if (const int sig = g_stop_signal.load(); sig != 0) {
        fmt::print(stderr, "mbstorm fuzz: interrupted by {}: exit code {}\n", signal_name(sig),
                   exit_code_for_signal(sig));
        return exit_code_for_signal(sig);
    }
    return fuzz_exit_code(r);
}

}  // namespace

// Grey-box: the target started by mbstorm and the coverage map handed to it.
void add_coverage_options(CLI::App* cmd, FuzzOptions& o) {
    cmd->add_option("--target-cmd", o.target_cmd,
                    "shell command that runs the target in the foreground: mbstorm starts it, "
                    "restarts it after a crash and stops it at the end");
    cmd->add_flag("--coverage", o.coverage,
                  "grey-box: read the edge coverage of a target built for it (AFL++'s "
                  "compilers, or clang -fsanitize-coverage=trace-pc-guard,trace-cmp with "
                  "share/mbstorm/coverage/mbstorm_coverage.c) and fuzz from what reaches new "
                  "edges; needs --target-cmd");
    cmd->add_option("--coverage-map-size", o.coverage_map_size,
                    "coverage map bytes, a power of two (passed on as AFL_MAP_SIZE)")
        ->check(CLI::Range(std::uint64_t{64}, std::uint64_t{1} << 24))
        ->capture_default_str();
    cmd->add_option("--coverage-report", o.coverage_report,
                    "coverage mode: write the target's functions no case reached to this file "
                    "('-': stdout), by file and line (a target built with pc-table too: "
                    "-fsanitize-coverage=trace-pc-guard,trace-cmp,pc-table)");
    cmd->add_option("--corpus", o.corpus_dir,
                    "coverage mode: save the corpus in this folder, one file per case; the "
                    "cases already there run first (resume)");
}

void add_fuzz_command(CLI::App& app, Action& action) {
    auto o = std::make_shared<FuzzOptions>();
    auto* cmd = app.add_subcommand(
        "fuzz", "Fuzz a Modbus TCP server: crashes, hangs, spec deviations, with reproducers");
    cmd->add_option(
        "--target", o->target,
        "server to fuzz: HOST[:PORT], [IPv6]:PORT or an IPv6 address, port 502 if omitted (802 "
        "with --transport tls; required but with --serial; loopback unless --allow-remote)");
    cmd->add_flag("--allow-remote", o->allow_remote, "allow a target outside 127.0.0.0/8 and ::1");
    cmd->add_option("--unit,-u", o->unit, "unit id the target answers")
        ->check(CLI::Range(0, 255))
        ->capture_default_str();
    cmd->add_option("--seed", o->seed,
                    "seed: the same seed against the same target gives the same cases")
        ->capture_default_str();
    add_duration_option(cmd, "--seconds,--duration,-d", o->duration_ns,
                        "stop after this long (60, 2s, 1m30s; a bare number is seconds)");
    add_count_option(cmd, "--cases", o->cases, "stop after this many cases");
    add_count_option(cmd, "--max-findings", o->max_findings,
                     "stop once this many distinct findings (root causes) are saved, the last "
                     "one minimised; 1 stops at the first (default 0: no limit; --seconds or "
                     "--cases still bound the run)",
                     0);
    add_duration_option(cmd, "--timeout", o->timeout_ns,
                        "answer timeout: longer is a hang (default 1s)");
    cmd->add_option("--connections,-c", o->lanes, "pipelined connections for well-framed cases")
        ->check(CLI::Range(1u, 64u))
        ->capture_default_str();
    cmd->add_option("--transport-share", o->isolated_per_mille,
                    "per mille of cases that need their own connection (transport, stateful)")
        ->check(CLI::Range(0u, 1000u))
        ->capture_default_str();
    cmd->add_option("--out", o->out_dir, "folder for findings (one sub-folder each)")
        ->capture_default_str();
    cmd->add_option("--restart-cmd", o->restart_cmd,
                    "shell command that restarts the target after a crash");
    add_coverage_options(cmd, *o);
    add_duration_option(cmd, "--restart-wait", o->restart_wait_ns,
                        "how long to wait for a crashed target to return (default 15s)");
    cmd->add_option("--baseline", o->baseline,
                    "an earlier run's --json or --sarif file: findings with a root cause it "
                    "lists are reported as known and do not fail the run (exit 0 when nothing "
                    "is new)");
    add_duration_option(cmd, "--wait-for-target", o->wait_for_target_ns,
                        "retry the first connect for up to this long (a target started just "
                        "before mbstorm, e.g. a CI service)");
    cmd->add_option("--json", o->json, "write a JSON summary to this file ('-': stdout)");
    cmd->add_option("--junit", o->junit, "write JUnit XML to this file ('-': stdout)");
    cmd->add_option("--sarif", o->sarif, "write SARIF 2.1.0 to this file ('-': stdout)");
    cmd->add_option("--html", o->html,
                    "write a self-contained HTML report to this file ('-': stdout): the run, "
                    "the device model, the findings and, with --coverage, edges over time");
    cmd->add_flag("--no-minimize", o->no_minimize, "do not shrink findings by delta debugging");
    cmd->add_flag("--naive", o->naive,
                  "baseline: random PDU bytes instead of the structure-aware generator");
    cmd->add_flag("--quiet,-q", o->quiet, "no progress lines");
    cmd->add_option("--dict", o->dict,
                    "AFL-style dictionary of your own addresses, values and byte strings");
    cmd->add_option("--state-range", o->state_range,
                    "holding registers/coils that stateful cases write and read back: FIRST-LAST "
                    "or 'all' (the whole map; only if nothing else writes there)")
        ->capture_default_str();
    cmd->add_option("--map", o->map,
                    "the device's register map, if you have it: TABLE=FIRST-LAST,... with TABLE "
                    "coils, discrete, input or holding (e.g. holding=1000-1099,coils=200-263); "
                    "default: learned by asking before fuzzing");
    cmd->add_option("--device-model", o->model,
                    "a device model saved by an earlier run (its --out folder's model.json) "
                    "instead of learning it again");
    // --model is run's closed or open loop.
    add_deprecated_option(cmd, "--model", "--device-model", o->model);
    cmd->add_flag("--no-model", o->no_model,
                  "do not learn the device's map: cases are not aimed inside it");
    cmd->add_option("--max-connections", o->max_connections,
                    "connection-capacity check: hold up to this many connections at once (0: "
                    "skip the check)")
        ->check(CLI::Range(0u, 1000000u))
        ->capture_default_str();
    add_transport_options(cmd, o->transport, TransportSide::Client);
    cmd->callback([o, cmd, &action] {
        o->state_given = cmd->count("--state-range") > 0;
        action = [o] {
            if (const Error e = check_transport(o->transport, "fuzz"); !e.ok())
                return fail("fuzz", e);
            if (o->target.empty() && o->transport.kind() != TransportKind::Serial)
                return usage_error("fuzz", "--target is required");
            return run_fuzz(*o);
        };
    });
}

}  // namespace mbstorm::cli
