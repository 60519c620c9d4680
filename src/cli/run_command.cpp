// `mbstorm run`: placeholder until the runr layer lands.
#include <fmt/format.h>

#include "cli/commands.hpp"

namespace mbstorm::cli {
void add_run_command(CLI::App& app, Action& action) {
    auto* cmd = app.add_subcommand("run", "Run a load test");
    cmd->callback([&action] {
        action = [] {
            fmt::print(stderr, "mbstorm run: not built yet\n");
            return kExitUsage;
        };
    });
}
}  // namespace mbstorm::cli
