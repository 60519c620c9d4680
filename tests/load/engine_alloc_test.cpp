// Counts every operator new in this test binary to show that a steady run allocates nothing.
// The reference slave runs in a forked child so that only the engine's allocations count.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <string>

#include "../support/counting_allocator.hpp"
#include "load/engine.hpp"
#include "server/server.hpp"

namespace mbstorm::load {
namespace {

using namespace std::chrono_literals;

// Runs the slave in a child process; the child exits when the parent closes `stop_pipe`.
struct ChildServer {
    pid_t pid = -1;
    int stop_fd = -1;
    std::uint16_t port = 0;

    bool start() {
        int port_pipe[2], stop_pipe[2];
        if (::pipe(port_pipe) != 0 || ::pipe(stop_pipe) != 0) return false;
        pid = ::fork();
        if (pid == 0) {
            ::close(port_pipe[0]);
            ::close(stop_pipe[1]);
            server::ServerConfig config;
            config.listen = "127.0.0.1:0";
            config.threads = 1;
            server::Server s(config);
            std::uint16_t p = s.start().ok() ? s.port() : 0;
            if (::write(port_pipe[1], &p, sizeof(p)) != sizeof(p)) ::_exit(1);
            char c;
            // Returns when the parent closes its end (or dies); bounded by the parent's test.
            [[maybe_unused]] auto n = ::read(stop_pipe[0], &c, 1);
            s.stop();
            ::_exit(0);
        }
        ::close(port_pipe[1]);
        ::close(stop_pipe[0]);
        stop_fd = stop_pipe[1];
        const bool ok = ::read(port_pipe[0], &port, sizeof(port)) == sizeof(port) && port != 0;
        ::close(port_pipe[0]);
        return ok;
    }
    ~ChildServer() {
        if (stop_fd >= 0) ::close(stop_fd);
        if (pid > 0) ::waitpid(pid, nullptr, 0);
    }
};

// keep_histograms: with an interval-log consumer, as run --hlog has (it must not allocate
// either; the histograms it is handed come from a reused pool).
void run_steady_state_check(LoadModel model, bool keep_histograms = false) {
    ChildServer child;
    ASSERT_TRUE(child.start());

    Plan plan;
    plan.port = child.port;
    Operation op;
    op.function = 0x03;
    op.first_address = 0;
    op.last_address = 999;
    op.quantity = 4;
    op.address_mode = AddressMode::Uniform;
    plan.operations = {op};
    plan.connections = 4;
    plan.depth = 8;
    plan.threads = 2;
    plan.model = model;
    plan.rate = 20000;
    plan.duration = 3500ms;

    // Allocation counts at the first and third progress report (about 1 s and 3 s in).
    std::uint64_t at_first = 0, at_third = 0;
    int reports = 0;
    EngineOptions options;
    options.on_progress = [&](const ProgressSnapshot&) {
        ++reports;
        if (reports == 1) at_first = mbstorm::testing::allocations();
        if (reports == 3) at_third = mbstorm::testing::allocations();
    };
    std::uint64_t logged_intervals = 0, logged_latencies = 0;
    if (keep_histograms) {
        options.on_interval_histograms = [&](const stats::IntervalHistograms& interval,
                                             std::chrono::system_clock::time_point) {
            ++logged_intervals;
            logged_latencies += interval.all.total_count();
        };
    }
    const LoadResult r = run_load(plan, options);
    ASSERT_TRUE(r.ok()) << r.error;
    ASSERT_GE(reports, 3);
    EXPECT_GT(at_first, 0u);  // the counter does count (setup allocates)
    EXPECT_GT(r.run.counters.ok(), 10000u);
    EXPECT_EQ(at_third - at_first, 0u) << "allocations during the steady part of the run";
    if (keep_histograms) {
        EXPECT_GE(logged_intervals, 3u);
        EXPECT_EQ(logged_latencies, r.run.latency.total_count());
    }
}

TEST(EngineAllocations, ClosedLoopSteadyStateAllocatesNothing) {
    run_steady_state_check(LoadModel::ClosedLoop);
}

TEST(EngineAllocations, OpenLoopSteadyStateAllocatesNothing) {
    run_steady_state_check(LoadModel::OpenLoop);
}

TEST(EngineAllocations, KeepingIntervalHistogramsAllocatesNothingInTheSteadyState) {
    run_steady_state_check(LoadModel::ClosedLoop, true);
}

}  // namespace
}  // namespace mbstorm::load
