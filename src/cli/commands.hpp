// Each subcommand registers itself on the CLI11 app and sets the action to run when chosen.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>

#include "cli/run_cli.hpp"

namespace mbstorm::cli {

// Exit codes shared by every subcommand.
inline constexpr int kExitOk = 0;
inline constexpr int kExitFailed = 1;  // thresholds breached, findings present
inline constexpr int kExitUsage = 2;   // bad input, bad flags, unreachable target

using Action = std::function<int()>;

void add_decode_command(CLI::App& app, Action& action);
void add_encode_command(CLI::App& app, Action& action);
void add_serve_command(CLI::App& app, Action& action);
void add_run_command(CLI::App& app, Action& action);
void add_fuzz_command(CLI::App& app, Action& action);
void add_replay_command(CLI::App& app, Action& action);
void add_read_command(CLI::App& app, Action& action);
void add_write_command(CLI::App& app, Action& action);

}  // namespace mbstorm::cli
