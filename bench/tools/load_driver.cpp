// Runs the load engine from flags and prints throughput and latency percentiles, so the engine
// can be measured before (and apart from) the CLI.
//
//   load_driver 127.0.0.1:5020 -c 64 --depth 16 -d 10 [--threads 2] [--rate 100000]
//               [--fc 3] [--quantity 1] [--range 1000] [--poisson] [--warmup 1]
#include <fmt/format.h>

#include <csignal>
#include <cstdlib>
#include <cstring>
#include <string>
#include <string_view>

#include "load/engine.hpp"
#include "stats/counters.hpp"

namespace {

std::atomic<bool> g_stop{false};

void on_signal(int) {
    g_stop = true;
}

[[noreturn]] void usage(const char* error = nullptr) {
    if (error) std::fprintf(stderr, "load_driver: %s\n", error);
    std::fprintf(stderr,
                 "usage: load_driver HOST:PORT [-c CONNECTIONS] [--depth N] [-d SECONDS] "
                 "[-n TRANSACTIONS]\n"
                 "       [--threads N] [--rate TX_PER_S] [--poisson] [--fc CODE] [--quantity N] "
                 "[--range N] [--warmup SECONDS] [--quiet]\n");
    std::exit(2);
}

}  // namespace

int main(int argc, char** argv) {
    using namespace mbstorm;
    load::Plan plan;
    load::Operation op;
    op.function = 0x03;
    op.quantity = 1;
    std::uint32_t range = 1000;
    std::string target;
    bool quiet = false;
    plan.duration = std::chrono::seconds(5);
    plan.threads = 0;

    for (int i = 1; i < argc; ++i) {
        const std::string_view a = argv[i];
        auto value = [&]() -> const char* {
            if (i + 1 >= argc) usage(fmt::format("{} needs a value", a).c_str());
            return argv[++i];
        };
        auto seconds = [](const char* v) {
            return std::chrono::duration_cast<load::Duration>(
                std::chrono::duration<double>(std::strtod(v, nullptr)));
        };
        if (a == "-c" || a == "--connections")
            plan.connections = std::strtoul(value(), nullptr, 10);
        else if (a == "--depth")
            plan.depth = std::strtoul(value(), nullptr, 10);
        else if (a == "-d" || a == "--duration")
            plan.duration = seconds(value());
        else if (a == "-n" || a == "--transactions")
            plan.transactions = std::strtoull(value(), nullptr, 10);
        else if (a == "--threads" || a == "-t")
            plan.threads = std::strtoul(value(), nullptr, 10);
        else if (a == "--rate") {
            plan.rate = std::strtod(value(), nullptr);
            plan.model = load::LoadModel::OpenLoop;
        } else if (a == "--poisson")
            plan.arrival = load::Arrival::Poisson;
        else if (a == "--fc")
            op.function = static_cast<std::uint8_t>(std::strtoul(value(), nullptr, 0));
        else if (a == "--quantity")
            op.quantity = static_cast<std::uint16_t>(std::strtoul(value(), nullptr, 10));
        else if (a == "--range")
            range = std::strtoul(value(), nullptr, 10);
        else if (a == "--warmup")
            plan.warmup = seconds(value());
        else if (a == "--quiet" || a == "-q")
            quiet = true;
        else if (a == "-h" || a == "--help")
            usage();
        else if (!a.empty() && a[0] != '-' && target.empty())
            target = a;
        else
            usage(fmt::format("unknown argument {}", a).c_str());
    }
    if (target.empty()) usage("no target given");
    const auto colon = target.rfind(':');
    if (colon == std::string::npos) usage("target must be HOST:PORT");
    plan.host = target.substr(0, colon);
    if (plan.host.size() > 2 && plan.host.front() == '[')
        plan.host = plan.host.substr(1, plan.host.size() - 2);
    plan.port = static_cast<std::uint16_t>(std::strtoul(target.c_str() + colon + 1, nullptr, 10));
    op.first_address = 0;
    op.last_address = static_cast<std::uint16_t>(std::min<std::uint32_t>(range, 65536) - 1);
    op.address_mode = load::AddressMode::Uniform;
    plan.operations = {op};

    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    load::EngineOptions options;
    options.stop = &g_stop;
    if (!quiet) {
        options.on_progress = [](const load::ProgressSnapshot& s) {
            std::fprintf(stderr,
                         "[%3llus] %10.0f tx/s  p50 %8.1f us  p99 %8.1f us  max %8.1f us  errors "
                         "%llu  conns %u\n",
                         static_cast<unsigned long long>(s.interval_index + 1),
                         s.transactions_per_second, s.p50_ns / 1e3, s.p99_ns / 1e3, s.max_ns / 1e3,
                         static_cast<unsigned long long>(s.errors), s.open_connections);
        };
    }
    const load::LoadResult r = load::run_load(plan, options);
    if (!r.ok()) std::fprintf(stderr, "load_driver: %s\n", r.error.text().c_str());
    const auto& h = r.run.latency;
    const auto& k = r.run.counters;
    fmt::print(
        "target {} model {} threads {} connections {} depth {}{}\n", r.run.metadata.target,
        stats::load_model_name(r.run.metadata.model), r.run.metadata.threads, plan.connections,
        plan.depth,
        plan.model == load::LoadModel::OpenLoop ? fmt::format(" rate {:.0f}/s", plan.rate) : "");
    fmt::print("transactions {} ok {} errors {} in {:.3f}s: {:.0f} tx/s\n", k.transactions_sent,
               k.ok(), k.errors(), r.run.metadata.measured_duration_ns / 1e9, r.run.throughput());
    fmt::print("latency us: p50 {:.1f}  p90 {:.1f}  p99 {:.1f}  p99.9 {:.1f}  max {:.1f}\n",
               h.value_at_percentile(50) / 1e3, h.value_at_percentile(90) / 1e3,
               h.value_at_percentile(99) / 1e3, h.value_at_percentile(99.9) / 1e3, h.max() / 1e3);
    for (std::size_t i = 0; i < stats::kOutcomeCount; ++i) {
        if (i == 0 || k.outcomes[i] == 0) continue;
        fmt::print("  {}: {}\n", stats::outcome_name(static_cast<stats::Outcome>(i)),
                   k.outcomes[i]);
    }
    if (plan.model == load::LoadModel::OpenLoop) {
        const auto& lag = r.run.schedule_lag;
        fmt::print("late sends {} (max lag {:.1f} us): engine {}, target {}\n",
                   lag.total().late_sends, lag.total().max_lag_ns / 1e3, lag.engine.late_sends,
                   lag.target.late_sends);
    }
    return r.ok() ? 0 : 1;
}
