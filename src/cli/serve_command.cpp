// `mbstorm serve`: the io_uring reference slave, with device description and fault injection.
#include <fmt/format.h>

#include <cstdio>
#include <memory>
#include <optional>
#include <string>

#include "cli/commands.hpp"
#include "cli/deprecated_option.hpp"
#include "cli/duration_option.hpp"
#include "cli/metrics_endpoint.hpp"
#include "cli/transport_options.hpp"
#include "net/kernel_tls.hpp"
#include "server/run.hpp"
#include "server/serial_server.hpp"
#include "server/server.hpp"
#include "slave/device_yaml.hpp"

namespace mbstorm::cli {
namespace {

struct ServeOptions {
    server::ServerConfig config;
    std::string device_file;
    std::string full_policy = "evict";
    std::string foreign_unit = "none";
    int only_unit = -1;
    std::uint64_t idle_timeout_ns = 0;
    std::uint64_t frame_timeout_ns = 10'000'000'000;
    std::string delay_kind;  // fixed | uniform | exponential
    std::uint64_t delay_ns = 0, delay_max_ns = 0;
    std::uint64_t stall_ns = 0, stall_every_ns = 0;
    double exception_rate = 0, drop_rate = 0, no_answer_rate = 0;
    int exception_code = 4;
    std::uint64_t seed = 0;
    bool stats = false;
    std::uint64_t duration_ns = 0;
    std::string metrics_listen;
    std::string backend = "auto";
    TransportOptions transport;
};

// `serve --serial`: the same models and handler on a tty, with a serial bus's manners: unit 0
// is a broadcast (executed, never answered) and units without a model stay silent.
int run_serial_serve(const ServeOptions& o, std::unique_ptr<slave::UnitModels> units) {
    if (!units) units = std::make_unique<slave::UnitModels>(slave::UnitModels::shared());
    units->broadcast_unit_zero = true;
    units->unknown_unit_policy = slave::UnknownUnitPolicy::Ignore;
    server::SerialServerConfig sc;
    sc.device = o.transport.serial_device;
    sc.line = serial_settings(o.transport);
    sc.framing = o.transport.framing_kind();
    sc.units = units.get();
    sc.only_unit = o.config.only_unit;
    sc.simulated = o.config.simulated;
    sc.faults = o.config.faults;
    server::SerialServer srv(std::move(sc));
    if (Error error = srv.open(); !error.ok()) return usage_error("serve", error.text());
    fmt::print("mbstorm serve: serving on {} (serial); Ctrl-C stops\n", srv.describe());
    if (o.config.faults.any()) fmt::print("mbstorm serve: fault injection is ON\n");
    std::fflush(stdout);
    const Error failure = server::run_serial_until_signal(
        srv, o.stats, static_cast<double>(o.duration_ns) / 1e9, stdout);
    if (failure.ok()) return kExitOk;
    fmt::print(stderr, "mbstorm serve: {}\n", failure.text());
    return kExitFailed;
}

int run_serve(ServeOptions& o) {
    if (const Error e = check_transport(o.transport, "serve"); !e.ok()) return fail("serve", e);
    auto& c = o.config;
    if (o.transport.kind() == TransportKind::RtuOverTcp) c.framing = codec::Framing::Rtu;
    if (o.transport.kind() == TransportKind::Tls) {
        Result<std::shared_ptr<net::TlsContext>> context = net::TlsContext::create(
            net::TlsSide::Server, {o.transport.tls_cert, o.transport.tls_key, o.transport.tls_ca});
        if (!context.ok()) return usage_error("serve", context.error().text());
        c.tls = std::move(context).value();
        for (const std::string& rule : o.transport.tls_roles)
            if (Error bad = c.tls_roles.add_rule(rule); !bad.ok())
                return usage_error("serve", bad.text());
        c.default_port = 802;
    } else if (!o.transport.tls_roles.empty()) {
        return usage_error("serve", "--tls-role needs --transport tls");
    }
    std::optional<slave::DeviceDescription> device;
    std::unique_ptr<slave::UnitModels> units;
    if (!o.device_file.empty()) {
        Result<slave::DeviceDescription> loaded = slave::load_device_file(o.device_file);
        if (!loaded.ok()) return usage_error("serve", loaded.error().text());
        device = std::move(loaded).value();
        c.faults = device->faults;
        // The device's role rules join --tls-role's (a role named in both may use either list).
        if (o.transport.kind() == TransportKind::Tls)
            for (const auto& [role, set] : device->tls_roles) c.tls_roles.allow(role, set);
        else if (!device->tls_roles.empty())
            fmt::print(stderr,
                       "mbstorm serve: warning: the device file's tls_roles apply only with "
                       "--transport tls\n");
        units = std::make_unique<slave::UnitModels>(slave::build_units(*device));
        // RTU over TCP: unit 0 is a broadcast, as on the serial line behind a gateway.
        if (o.transport.kind() == TransportKind::RtuOverTcp) units->broadcast_unit_zero = true;
        c.units = units.get();
        c.simulated = device->simulated;
    }
    // Flags override the device file's fault settings.
    auto& f = c.faults;
    if (!o.delay_kind.empty()) {
        using K = slave::DelayConfig::Kind;
        if (o.delay_kind == "fixed")
            f.delay = {K::Fixed, o.delay_ns, 0, 0, 0};
        else if (o.delay_kind == "uniform")
            f.delay = {K::Uniform, 0, o.delay_ns, o.delay_max_ns, 0};
        else if (o.delay_kind == "exponential")
            f.delay = {K::Exponential, 0, 0, 0, o.delay_ns};
    } else if (o.delay_ns) {
        f.delay = {slave::DelayConfig::Kind::Fixed, o.delay_ns, 0, 0, 0};
    }
    if (o.stall_ns || o.stall_every_ns) f.stall = {o.stall_ns, o.stall_every_ns};
    if (o.exception_rate) f.exception_rate = o.exception_rate;
    f.exception_code = static_cast<codec::ExceptionCode>(o.exception_code);
    if (o.drop_rate) f.drop_rate = o.drop_rate;
    if (o.no_answer_rate) f.no_answer_rate = o.no_answer_rate;
    if (o.seed) f.seed = o.seed;
    if (Error problem = slave::validate(f); !problem.ok())
        return usage_error("serve", problem.text());

    c.full_policy = o.full_policy == "refuse" ? server::FullPolicy::Refuse
                                              : server::FullPolicy::EvictOldestIdle;
    c.idle_timeout_ms = o.idle_timeout_ns / 1'000'000;
    c.frame_timeout_ms = o.frame_timeout_ns / 1'000'000;
    if (o.only_unit >= 0) {
        c.only_unit = static_cast<std::uint8_t>(o.only_unit);
        c.foreign_unit = o.foreign_unit == "exception" ? server::ForeignUnitPolicy::GatewayException
                                                       : server::ForeignUnitPolicy::NoAnswer;
    }

    if (o.transport.kind() == TransportKind::Serial) return run_serial_serve(o, std::move(units));
    net::parse_backend_choice(o.backend, c.backend_choice);  // checked by CLI11
    server::block_stop_signals();
    server::Server srv(c);
    if (Error error = srv.start(); !error.ok()) return usage_error("serve", error.text());
    // The endpoint first, then the transport: scripts take the word after "listening on".
    fmt::print("mbstorm serve: listening on {} ({}, {} thread{}, {}); Ctrl-C stops\n",
               srv.endpoint(), transport_name(o.transport.kind()), srv.threads(),
               srv.threads() == 1 ? "" : "s", srv.describe_io());
    if (!srv.backend_reason().empty())
        fmt::print("mbstorm serve: backend: epoll; {}\n", srv.backend_reason());
    if (!srv.warning().empty()) fmt::print(stderr, "mbstorm serve: warning: {}\n", srv.warning());
    if (f.any()) fmt::print("mbstorm serve: fault injection is ON\n");
    if (c.tls) fmt::print("mbstorm serve: {}\n", net::describe_tls_path());
    std::fflush(stdout);
    net::HttpServer metrics;
    if (!o.metrics_listen.empty() &&
        !start_metrics_endpoint(metrics, o.metrics_listen, "serve",
                                [&srv] { return format_serve_metrics(srv.stats()); }))
        return kExitUsage;
    server::RunOptions run;
    run.print_stats = o.stats;
    run.max_seconds = static_cast<double>(o.duration_ns) / 1e9;
    server::run_until_signal(srv, run);
    return kExitOk;
}

}  // namespace

void add_serve_command(CLI::App& app, Action& action) {
    auto o = std::make_shared<ServeOptions>();
    auto* cmd = app.add_subcommand(
        "serve", "Run the reference Modbus TCP slave (io_uring, or epoll where it is refused)");
    cmd->add_option("--listen,-l", o->config.listen,
                    "address to listen on: HOST[:PORT], [IPv6]:PORT or an IPv6 address, "
                    "port 502 if omitted (802 with --transport tls); :PORT, 0.0.0.0 or [::] "
                    "accept connections from every interface")
        ->capture_default_str();
    add_transport_options(cmd, o->transport, TransportSide::Server);
    add_deprecated_option(cmd, "-t", "--threads", o->config.threads);
    cmd->add_option("--threads", o->config.threads,
                    "worker threads, each with its own ring (0: one per core)")
        ->check(CLI::Range(0u, 1024u));
    cmd->add_option("--backend", o->backend,
                    "event source: io_uring, epoll (where io_uring is refused, e.g. Docker 25+'s "
                    "default seccomp profile), or auto: io_uring when this process may use it")
        ->check(CLI::IsMember({"auto", "io_uring", "epoll"}))
        ->capture_default_str();
    cmd->add_option("--device", o->device_file,
                    "YAML device description: tables, initial data, simulated inputs, faults");
    cmd->add_flag("--stats", o->stats, "print a line of statistics every second");
    cmd->add_option("--metrics-listen", o->metrics_listen,
                    "serve live metrics at http://HOST:PORT/metrics (Prometheus text format); "
                    "port 0: any free port, printed on stderr");
    add_duration_option(cmd, "--duration,-d", o->duration_ns,
                        "stop by itself after this long (default: until Ctrl-C)");
    cmd->add_option("--max-connections", o->config.max_connections, "connection limit (0: none)")
        ->capture_default_str();
    cmd->add_option("--full-policy", o->full_policy,
                    "at the limit: evict the oldest idle connection, or refuse the new one")
        ->check(CLI::IsMember({"evict", "refuse"}))
        ->capture_default_str();
    add_duration_option(cmd, "--idle-timeout", o->idle_timeout_ns,
                        "close connections idle this long (default: never)");
    add_duration_option(cmd, "--frame-timeout", o->frame_timeout_ns,
                        "close a connection whose started frame is not complete this long after "
                        "its first byte, or a TLS handshake not done this long after it began "
                        "(default 10s; 0: no bound)");
    cmd->add_option("--max-outstanding", o->config.max_outstanding,
                    "answer requests beyond this many unanswered ones per connection with "
                    "exception 06 (0: no cap)")
        ->check(CLI::Range(0u, 65535u));
    cmd->add_option("--only-unit", o->only_unit, "answer only this unit id")
        ->check(CLI::Range(0, 255));
    cmd->add_option("--foreign-unit", o->foreign_unit,
                    "other unit ids: no answer, or exception 0B like a gateway")
        ->check(CLI::IsMember({"none", "exception"}));
    cmd->add_option("--delay-kind", o->delay_kind, "response delay distribution")
        ->check(CLI::IsMember({"fixed", "uniform", "exponential"}));
    add_duration_option(cmd, "--delay", o->delay_ns,
                        "response delay (fixed value, uniform minimum, or exponential mean)");
    add_duration_option(cmd, "--delay-max", o->delay_max_ns, "uniform delay maximum");
    add_duration_option(cmd, "--stall", o->stall_ns, "hold all responses this long ...");
    add_duration_option(cmd, "--stall-every", o->stall_every_ns, "... once every this long");
    add_rate_option(cmd, "--exception-rate", o->exception_rate,
                    "answer this share of requests with an exception");
    cmd->add_option("--exception-code", o->exception_code, "code of injected exceptions")
        ->check(CLI::Range(1, 255));
    add_rate_option(cmd, "--drop-rate", o->drop_rate,
                    "close the connection instead of answering, for this share");
    add_rate_option(cmd, "--no-answer-rate", o->no_answer_rate,
                    "leave this share of requests unanswered");
    cmd->add_option("--seed", o->seed, "seed for fault injection draws");
    cmd->callback([o, &action] { action = [o] { return run_serve(*o); }; });
}

}  // namespace mbstorm::cli
