// `mbstorm run`: a load test. With no --target it starts the built-in reference slave on an
// ephemeral loopback port so that it works out of the box.
#include <fmt/format.h>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "cli/commands.hpp"
#include "cli/deprecated_option.hpp"
#include "cli/distributed_options.hpp"
#include "cli/duration_option.hpp"
#include "cli/packaged_files.hpp"
#include "cli/run_output.hpp"
#include "cli/run_scenario.hpp"
#include "cli/transport_options.hpp"
#include "codec/address.hpp"
#include "codec/function_code.hpp"
#include "codec/values.hpp"
#include "load/plan.hpp"
#include "scenario/scenario.hpp"

namespace mbstorm::cli {
namespace {

constexpr std::uint8_t kDefaultFunction = codec::to_byte(codec::FunctionCode::ReadHoldingRegisters);

// "0x05 write_single_coil, 0x06 write_single_register and 0x16 mask_write_register": the
// functions whose quantity is always one.
std::string single_item_functions() {
    std::vector<std::string> labels;
    for (const codec::FunctionInfo& f : codec::public_functions()) {
        if (f.quantity.max == 1) labels.push_back(codec::function_label(codec::to_byte(f.code)));
    }
    std::string text;
    for (std::size_t i = 0; i < labels.size(); ++i) {
        if (i > 0) text += i + 1 == labels.size() ? " and " : ", ";
        text += labels[i];
    }
    return text;
}

struct RunOptions {
    load::Plan plan;
    std::string target;
    std::string function = std::string(codec::function_name(kDefaultFunction));
    std::string address = "0";
    std::string addr_mode = "sequential";
    std::string model;    // "": not given (open loop when --rate is)
    std::string arrival;  // "": not given (even)
    int value = 0;
    int quantity = 0;  // 0: not given (10, or 1 for the single-item functions)
    std::uint64_t duration_ns = 10'000'000'000ULL;
    std::uint64_t warmup_ns = 0, timeout_ns = 1'000'000'000ULL,
                  connect_timeout_ns = 3'000'000'000ULL;
    unsigned slave_threads = 0;
    bool quiet = false;
    OutputFiles outputs;
    std::string scenario_file;  // `mbstorm run FILE`: see run_scenario.cpp
    bool print_scenario = false;
    std::string junit;
    std::vector<std::string> thresholds;  // --threshold EXPR (repeatable)
    bool fail_on_plan_shortfall = false;
    std::string shard;     // --shard I/N (else the environment)
    std::string start_at;  // --start-at TIME
    std::string backend = "auto";
    TransportOptions transport;
    bool depth_given = false;  // --depth on the command line (not its default)
};

// --shard (or the environment), --start-at and --backend into the request, or the usage
// error.
Error distributed_options(const RunOptions& o, ScenarioRunRequest& request) {
    net::parse_backend_choice(o.backend, request.backend);  // checked by CLI11
    if (Error e = resolve_shard(o.shard, std::getenv(kShardIndexEnv), std::getenv(kShardCountEnv),
                                request.shard);
        !e.ok())
        return e;
    if (o.start_at.empty()) return {};
    std::chrono::system_clock::time_point at;
    if (Error e = parse_start_at(o.start_at, std::chrono::system_clock::now(), at); !e.ok())
        return e;
    request.start_at = at;
    return {};
}

// --model, --rate and --arrival into the plan's model (load::settle_load_model's rule, as a
// scenario file's keys); "" or the contradiction, naming both flags.
std::string settle_model(RunOptions& o) {
    load::LoadModelAsked asked;
    if (!o.model.empty())
        asked.model = o.model == "open" ? load::LoadModel::OpenLoop : load::LoadModel::ClosedLoop;
    asked.rate = o.plan.rate;
    asked.arrival_given = !o.arrival.empty();
    switch (load::settle_load_model(asked, o.plan.model)) {
        case load::LoadModelConflict::None:
            return {};
        case load::LoadModelConflict::RateInClosedLoop:
            return fmt::format(
                "--model closed and --rate {:g} contradict each other: a rate paces an open "
                "loop; drop --rate, or use --model open",
                o.plan.rate);
        case load::LoadModelConflict::OpenLoopWithoutRate:
            return "--model open needs --rate (transactions per second, e.g. --rate 50000)";
        case load::LoadModelConflict::ArrivalInClosedLoop:
            return fmt::format(
                "--arrival {} {}: arrivals are spaced only in an open loop; add --rate N or "
                "drop --arrival",
                o.arrival, o.model.empty() ? "needs --rate" : "contradicts --model closed");
    }
    return {};
}

// Fills the single-operation plan from flags; returns an error message or "".
std::string build_plan(RunOptions& o) {
    auto& p = o.plan;
    if (o.transport.kind() == TransportKind::RtuOverTcp) {
        p.framing = codec::Framing::Rtu;
        // One request at a time per connection: RTU has no transaction ids.
        if (!o.depth_given) p.depth = 1;
    }
    // Starts from the operation the flags filled (--unit, --zipf).
    load::Operation op = p.operations.at(0);
    if (auto error = codec::parse_function_code(o.function, op.function); !error.empty())
        return "--fc: " + error;
    // One address rule for every subcommand: codec/address.hpp.
    codec::AddressRange range;
    if (auto error =
            codec::parse_address_range(o.address, codec::function_table(op.function), range);
        !error.empty())
        return fmt::format("--addr {}", error);
    op.first_address = range.first;
    if (range.is_range) op.last_address = range.last;
    if (o.addr_mode == "uniform")
        op.address_mode = load::AddressMode::Uniform;
    else if (o.addr_mode == "zipf")
        op.address_mode = load::AddressMode::Zipf;
    op.values.value = static_cast<std::uint16_t>(o.value);
    op.name = std::string(codec::function_name(op.function));
    if (op.name.empty()) op.name = fmt::format("fc{:02x}", op.function);
    // No --quantity: 10 for reads, 1 where the function has a fixed quantity of one.
    op.quantity = o.quantity;
    if (op.quantity == 0) op.quantity = codec::quantity_range(op.function).max == 1 ? 1 : 10;
    p.operations.assign(1, op);

    if (auto error = settle_model(o); !error.empty()) return error;
    p.arrival = o.arrival == "poisson" ? load::Arrival::Poisson : load::Arrival::Even;
    p.duration = std::chrono::nanoseconds(o.duration_ns);
    p.warmup = std::chrono::nanoseconds(o.warmup_ns);
    p.transaction_timeout = std::chrono::nanoseconds(o.timeout_ns);
    p.connect_timeout = std::chrono::nanoseconds(o.connect_timeout_ns);
    if (o.duration_ns == 0 && p.transactions == 0)
        return "-d 0 needs --transactions N to end the run";
    return {};
}

int run_load_test(RunOptions& o) {
    if (o.plan.operations.empty()) o.plan.operations.push_back({});
    if (auto err = build_plan(o); !err.empty()) return usage_error("run", err);
    if (o.print_scenario) return print_flag_scenario(o.plan, o.target, o.thresholds);
    if (!o.junit.empty() && o.thresholds.empty() && !o.fail_on_plan_shortfall)
        return usage_error("run",
                           "--junit writes thresholds as test cases: give --threshold EXPR "
                           "(e.g. 'p99 < 5ms'; repeatable), --fail-on-plan-shortfall or a "
                           "scenario FILE");
    auto& plan = o.plan;
    if (o.transport.kind() == TransportKind::Serial) {
        if (!o.target.empty())
            return usage_error("run", "--target and --serial exclude each other");
        // One master on the line, one request at a time.
        plan.serial = {o.transport.serial_device, serial_settings(o.transport),
                       o.transport.framing_kind()};
        plan.connections = 1;
        plan.depth = 1;
        plan.threads = 1;
        // Writes to a tty that is not a pseudo-terminal need leave: the engine checks.
    }
    if (const Error problems = load::validate_plan(plan); !problems.ok())
        return usage_error("run", problems.text());

    // A flag-only run is a one-operation scenario: the runner starts the embedded slave when
    // there is no target, and reports the same way.
    scenario::Scenario s = scenario::scenario_from_plan(plan, o.target);
    if (Error e = client_tls(o.transport, s.plan.tls); !e.ok()) return fail("run", e);
    if (s.plan.tls && o.target.empty())
        return usage_error("run",
                           "--transport tls needs --target (the embedded slave is plain TCP)");
    s.plan.tls_resume = o.transport.tls_resume;
    s.name.clear();
    s.slave_threads = o.slave_threads;
    if (const Error e = add_threshold_flags(o.thresholds, s); !e.ok())
        return usage_error("run", e.text());
    fmt::print(
        stderr, "mbstorm run: load test of {}: {} connection{} x depth {}, {} {}, {}\n",
        !plan.serial.device.empty()
            ? fmt::format("serial line {} ({} {})", plan.serial.device,
                          net::describe(plan.serial.line), codec::framing_name(plan.serial.framing))
        : o.target.empty() ? std::string("the embedded reference slave (no --target given)")
                           : o.target,
        plan.connections, plan.connections == 1 ? "" : "s", plan.depth, plan.operations[0].name,
        plan.model == load::LoadModel::OpenLoop ? fmt::format("open loop at {:.0f} tx/s", plan.rate)
                                                : std::string("closed loop"),
        plan.duration.count() ? fmt::format("for {:.3g}s", plan.duration.count() / 1e9)
                              : fmt::format("for {} transactions", plan.transactions));
    ScenarioRunRequest request;
    request.fail_on_plan_shortfall = o.fail_on_plan_shortfall;
    request.junit = o.junit;
    request.quiet = o.quiet;
    request.outputs = o.outputs;
    if (const Error e = distributed_options(o, request); !e.ok()) return fail("run", e);
    return run_resolved_scenario(s, request);
}

// Flags given next to a scenario FILE override its values; the single-operation flags have no
// meaning there (the file lists the operations).
int run_with_scenario(const RunOptions& o, const CLI::App& cmd) {
    for (const char* flag : {"--fc", "--addr", "--quantity", "--count", "--unit", "--addr-mode",
                             "--zipf", "--value", "--model", "--arrival"}) {
        if (cmd.count(flag) != 0)
            return usage_error(
                "run",
                fmt::format("{} cannot be used with a scenario file (set it in the file)", flag));
    }
    ScenarioRunRequest r;
    if (Error e = client_tls(o.transport, r.tls); !e.ok()) return fail("run", e);
    if (o.transport.kind() == TransportKind::Serial) {
        if (cmd.count("--target") != 0)
            return usage_error("run", "--target and --serial exclude each other");
        for (const char* flag : {"--connections", "--depth", "--threads"}) {
            if (cmd.count(flag) != 0)
                return usage_error("run", fmt::format("{} does not apply to a serial line (one "
                                                      "master, one request at a time)",
                                                      flag));
        }
        r.serial = {o.transport.serial_device, serial_settings(o.transport),
                    o.transport.framing_kind()};
    }
    r.tls_resume = o.transport.tls_resume;
    r.file = o.scenario_file;
    r.print = o.print_scenario;
    r.junit = o.junit;
    r.thresholds = o.thresholds;
    r.fail_on_plan_shortfall = o.fail_on_plan_shortfall;
    r.quiet = o.quiet;
    r.outputs = o.outputs;
    if (const Error e = distributed_options(o, r); !e.ok()) return fail("run", e);
    auto& ov = r.overrides;
    const auto& p = o.plan;
    auto given = [&cmd](const char* flag) { return cmd.count(flag) != 0; };
    if (given("--target")) ov.target = o.target;
    if (given("--duration")) ov.duration = std::chrono::nanoseconds(o.duration_ns);
    if (given("--warmup")) ov.warmup = std::chrono::nanoseconds(o.warmup_ns);
    if (given("--connections")) ov.connections = p.connections;
    if (given("--depth")) ov.depth = p.depth;
    if (given("--transport")) ov.framing = o.transport.framing_kind();
    if (given("--threads")) ov.threads = p.threads;
    if (given("--rate")) ov.rate = p.rate;
    if (given("--transactions")) ov.transactions = p.transactions;
    if (given("--timeout")) ov.transaction_timeout = std::chrono::nanoseconds(o.timeout_ns);
    if (given("--connect-timeout"))
        ov.connect_timeout = std::chrono::nanoseconds(o.connect_timeout_ns);
    if (given("--connect-rate")) ov.connect_rate = p.connect_rate;
    if (given("--source-addr")) ov.source_addresses = p.source_addresses;
    if (given("--seed")) ov.seed = p.seed;
    if (given("--slave-threads")) ov.slave_threads = o.slave_threads;
    ov.allow_writes = p.allow_writes;
    return run_scenario_file(r);
}

// How much load: connections, depth, threads, duration, the loop model and the rate.
void add_load_shape_options(CLI::App* cmd, RunOptions& o) {
    auto& p = o.plan;
    cmd->add_option("-c,--connections", p.connections, "connections")
        ->check(CLI::Range(1u, load::kMaxConnections))
        ->capture_default_str();
    cmd->add_option("--depth", p.depth, "outstanding transactions per connection (pipelining)")
        ->check(CLI::Range(1u, load::kMaxDepth))
        ->capture_default_str();
    cmd->add_option("--threads", p.threads,
                    "engine threads, one ring each (0: the cores left over)")
        ->check(CLI::Range(0u, load::kMaxThreads));
    cmd->add_option("--slave-threads", o.slave_threads,
                    "threads of the embedded slave (0: half the cores)")
        ->check(CLI::Range(0u, 1024u));
    add_duration_option(cmd, "-d,--duration", o.duration_ns,
                        "how long to measure (default 10s; 0 with --transactions)");
    cmd->add_option("-n,--transactions", p.transactions,
                    "stop after this many measured transactions (warm-up sends not counted)");
    add_duration_option(cmd, "--warmup", o.warmup_ns, "run this long first without recording");
    cmd->add_option("--model", o.model,
                    "closed loop (keep --depth outstanding) or open loop (--rate)")
        ->check(CLI::IsMember({"closed", "open"}));
    add_number_option(cmd, "-R,--rate", p.rate, 0.0, load::kMaxRate,
                      "open loop: total transactions per second; latency is measured from each "
                      "transaction's intended send time (coordinated-omission corrected)");
    cmd->add_option("--arrival", o.arrival, "open-loop arrivals: evenly spread or Poisson")
        ->check(CLI::IsMember({"even", "poisson"}));
}

// What each transaction asks: function, addresses, quantity, unit, values.
void add_request_options(CLI::App* cmd, RunOptions& o) {
    auto& p = o.plan;
    cmd->add_option("--fc,-f", o.function,
                    "function code (default " + codec::function_label(kDefaultFunction) +
                        "): " + std::string(codec::kFunctionCodeForms));
    cmd->add_option("--addr,-a", o.address, std::string(codec::kAddressRuleHelp));
    cmd->add_option(
           "--quantity", o.quantity,
           "registers or bits per request (default 10; 1 for " + single_item_functions() + ")")
        ->check(CLI::Range(1, 2000));
    add_deprecated_option(cmd, "--count", "--quantity", o.quantity)->check(CLI::Range(1, 2000));
    cmd->add_option("--unit,-u", p.operations[0].unit_id, "unit id")->check(CLI::Range(0, 255));
    cmd->add_option("--addr-mode", o.addr_mode, "how addresses move within --addr's range")
        ->check(CLI::IsMember({"sequential", "uniform", "zipf"}));
    add_number_option(cmd, "--zipf", p.operations[0].zipf_exponent, 0.0, load::kMaxZipfExponent,
                      "zipf exponent");
    cmd->add_option("--value", o.value, "value written by write operations")
        ->check(CLI::Range(0, 65535));
}

// How the run connects and what it writes out: timeouts, sources, outputs, shards, backend.
void add_connection_options(CLI::App* cmd, RunOptions& o) {
    auto& p = o.plan;
    add_duration_option(cmd, "--timeout", o.timeout_ns, "per-transaction timeout (default 1s)");
    add_duration_option(cmd, "--connect-timeout", o.connect_timeout_ns,
                        "connect timeout (default 3s)");
    add_number_option(cmd, "--connect-rate", p.connect_rate, 1.0, 1e7,
                      "new connections per second");
    cmd->add_option("--source-addr", p.source_addresses,
                    "local addresses to connect from, round-robin: a comma list of addresses "
                    "and ranges (127.0.0.1-127.0.0.20,::1); each adds its own ephemeral ports");
    cmd->add_flag("--allow-writes", p.allow_writes,
                  "allow write function codes to a target outside loopback");
    cmd->add_option("--seed", p.seed, "seed for address and value generators");
    cmd->add_flag("-q,--quiet", o.quiet, "no live progress line");
    add_output_options(cmd, o.outputs);
    add_run_identity_options(cmd, o.outputs);
    cmd->add_option("--shard", o.shard,
                    fmt::format("run shard I of N of the plan (I counts from 0, e.g. 0/3): its "
                                "part of the connections, rates, stages, transactions and "
                                "addresses; default from the environment {} and {} "
                                "(a Kubernetes Indexed Job); merge the shards with mbstorm merge",
                                kShardIndexEnv, kShardCountEnv));
    cmd->add_option("--backend", o.backend,
                    "event source: io_uring, epoll (where io_uring is refused, e.g. Docker 25+'s "
                    "default seccomp profile), or auto: io_uring when this process may use it")
        ->check(CLI::IsMember({"auto", "io_uring", "epoll"}))
        ->capture_default_str();
    cmd->add_option("--start-at", o.start_at,
                    "connect now, start sending (warm-up first) at this wall-clock time: RFC 3339 "
                    "(2026-11-24T14:00:00Z, or with an offset) or seconds since the epoch; a "
                    "late start begins at once and reports by how much");
}

// A scenario file instead of flags, and the run's verdict: thresholds, JUnit, shortfalls.
void add_scenario_options(CLI::App* cmd, RunOptions& o) {
    cmd->add_option("file", o.scenario_file,
                    "scenario file (YAML, see scenarios/README.md), or the name of a packaged "
                    "one (quickstart, ci-gate, soak, ...); flags override its values")
        ->transform(CLI::Validator(
            [](std::string& arg) {
                const std::string found = find_scenario(arg);
                if (found.empty())
                    return fmt::format("no scenario file '{}'{}", arg,
                                       packaged_dir("scenarios").empty()
                                           ? std::string()
                                           : " (nor a packaged scenario of that name: " +
                                                 packaged_dir("scenarios") + ")");
                arg = found;
                return std::string();
            },
            "FILE|NAME"));
    cmd->add_flag("--print-scenario", o.print_scenario,
                  "print the fully resolved scenario (defaults included) as YAML and exit");
    cmd->add_option("--junit", o.junit, "write the thresholds as JUnit XML test cases");
    cmd->add_option("--threshold", o.thresholds,
                    "pass/fail check, as in a scenario's thresholds (e.g. 'p99 < 5ms', "
                    "'error_rate < 0.1%', 'throughput > 50000/s'); repeatable; a breach exits 1")
        ->expected(1)
        ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
    cmd->add_flag("--fail-on-plan-shortfall", o.fail_on_plan_shortfall,
                  "exit 1 when the plan was not carried out (connections not opened, the rate "
                  "not reached, the run cut short), thresholds or not");
}

}  // namespace

void add_run_command(CLI::App& app, Action& action) {
    auto o = std::make_shared<RunOptions>();
    o->plan.operations.push_back({});
    o->plan.connections = 16;
    o->plan.depth = 16;
    auto* cmd = app.add_subcommand(
        "run", "Run a Modbus TCP load test (against the built-in slave when no --target)");
    cmd->add_option("--target", o->target,
                    "server to test: HOST[:PORT], [IPv6]:PORT or an IPv6 address, port 502 if "
                    "omitted (default: start the embedded slave)");
    add_transport_options(cmd, o->transport, TransportSide::Client);
    add_load_shape_options(cmd, *o);
    add_request_options(cmd, *o);
    add_connection_options(cmd, *o);
    add_scenario_options(cmd, *o);
    cmd->callback([o, cmd, &action] {
        action = [o, cmd] {
            OutputFiles outputs = o->outputs;
            outputs.junit = o->junit;
            if (const Error e = stdout_conflict(outputs); !e.ok()) return fail("run", e);
            if (const Error e = check_transport(o->transport, "run"); !e.ok())
                return fail("run", e);
            o->depth_given = cmd->count("--depth") != 0;
            return o->scenario_file.empty() ? run_load_test(*o) : run_with_scenario(*o, *cmd);
        };
    });
}

}  // namespace mbstorm::cli
