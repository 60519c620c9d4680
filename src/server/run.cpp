#include "server/run.hpp"

#include <signal.h>

#include <algorithm>
#include <cerrno>
#include <ctime>

#include "net/clock.hpp"

namespace mbstorm::server {

void block_stop_signals() noexcept {
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &set, nullptr);
}

void run_until_signal(Server& server, const RunOptions& options) {
    block_stop_signals();
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    const std::int64_t start = net::now_ns();
    const double interval = options.stats_interval_s > 0 ? options.stats_interval_s : 1.0;
    std::int64_t next = start + static_cast<std::int64_t>(interval * 1e9);
    ServerStats before = server.stats();
    // -d 300ms ends at 300 ms, not at the next whole-second statistics line.
    const std::int64_t end =
        options.max_seconds > 0 ? start + static_cast<std::int64_t>(options.max_seconds * 1e9) : 0;
    for (;;) {
        std::int64_t now = net::now_ns();
        if (end != 0 && now >= end) break;
        std::int64_t wait = (end != 0 ? std::min(next, end) : next) - now;
        if (wait < 0) wait = 0;
        timespec ts{static_cast<time_t>(wait / net::kNsPerSec),
                    static_cast<long>(wait % net::kNsPerSec)};
        int sig = sigtimedwait(&set, nullptr, &ts);
        if (sig == SIGINT || sig == SIGTERM) break;
        now = net::now_ns();
        if (now >= next) {
            if (options.print_stats) {
                ServerStats s = server.stats();
                std::fprintf(
                    options.out, "%s\n",
                    format_stats_line(s, before, static_cast<double>(now - start) / 1e9, interval)
                        .c_str());
                std::fflush(options.out);
                before = s;
            }
            next += static_cast<std::int64_t>(interval * 1e9);
        }
    }
    server.stop();
    std::fprintf(
        options.out, "%s",
        format_summary(server.stats(), static_cast<double>(net::now_ns() - start) / 1e9).c_str());
    std::fflush(options.out);
}

}  // namespace mbstorm::server
