// Starts the reference slave in-process for the interop scripts and the server bench, so they
// do not depend on the `mbstorm serve` CLI. Prints "PORT <n>" once listening.
//
//   mbstorm_test_server [--listen host:port] [--threads N] [--stats] [--seconds S]
//                       [--max-outstanding N] [--unit U] [--idle-ms MS]
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "net/features.hpp"
#include "server/run.hpp"
#include "server/server.hpp"

int main(int argc, char** argv) {
    using namespace mbstorm;
    server::ServerConfig config;
    config.listen = "127.0.0.1:0";
    config.threads = 1;
    server::RunOptions run;
    for (int i = 1; i < argc; ++i) {
        std::string a = argv[i];
        auto value = [&]() -> const char* {
            if (i + 1 >= argc) {
                std::fprintf(stderr, "missing value for %s\n", a.c_str());
                std::exit(2);
            }
            return argv[++i];
        };
        if (a == "--listen")
            config.listen = value();
        else if (a == "--port")
            config.listen = std::string("127.0.0.1:") + value();
        else if (a == "--threads")
            config.threads = static_cast<unsigned>(std::atoi(value()));
        else if (a == "--stats")
            run.print_stats = true;
        else if (a == "--seconds")
            run.max_seconds = std::atof(value());
        else if (a == "--max-outstanding")
            config.max_outstanding = static_cast<unsigned>(std::atoi(value()));
        else if (a == "--unit")
            config.only_unit = static_cast<std::uint8_t>(std::atoi(value()));
        else if (a == "--idle-ms")
            config.idle_timeout_ms = static_cast<std::uint64_t>(std::atoll(value()));
        else if (a == "--no-buf-ring")
            config.use_buf_ring = false;
        else {
            std::fprintf(stderr, "unknown option %s\n", a.c_str());
            return 2;
        }
    }
    server::block_stop_signals();
    server::Server srv(config);
    if (const Error error = srv.start(); !error.ok()) {
        std::fprintf(stderr, "mbstorm_test_server: %s\n", error.text().c_str());
        return 1;
    }
    std::fprintf(stderr, "%s\n%s\n", net::describe(net::features()).c_str(),
                 srv.describe_io().c_str());
    if (!srv.warning().empty()) std::fprintf(stderr, "warning: %s\n", srv.warning().c_str());
    std::printf("PORT %u\n", srv.port());
    std::fflush(stdout);
    server::run_until_signal(srv, run);
    return 0;
}
