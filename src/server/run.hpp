// Runs a started Server until SIGINT/SIGTERM: optional `--stats` lines once per second, then
// a graceful stop and the summary. Used by `mbstorm serve` and the test tool.
#pragma once

#include <cstdio>

#include "server/server.hpp"

namespace mbstorm::server {

struct RunOptions {
    bool print_stats = false;
    double stats_interval_s = 1.0;
    double max_seconds = 0;  // 0: until a signal
    std::FILE* out = stdout;
};

// Blocks SIGINT/SIGTERM in the caller (do it before start() so that workers inherit the mask),
// then waits. Nothing fails here: a server that started serves until it is stopped.
void block_stop_signals() noexcept;
void run_until_signal(Server& server, const RunOptions& options);

}  // namespace mbstorm::server
