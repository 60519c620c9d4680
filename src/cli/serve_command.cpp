// `mbstorm serve`: placeholder until the server layer lands.
#include <fmt/format.h>

#include "cli/commands.hpp"

namespace mbstorm::cli {
void add_serve_command(CLI::App& app, Action& action) {
    auto* cmd = app.add_subcommand("serve", "Run the reference Modbus TCP slave");
    cmd->callback([&action] {
        action = [] {
            fmt::print(stderr, "mbstorm serve: not built yet\n");
            return kExitUsage;
        };
    });
}
}  // namespace mbstorm::cli
