// Each subcommand registers itself on the CLI11 app and sets the action to run when chosen.
#pragma once

#include <CLI/CLI.hpp>

#include <fmt/format.h>

#include <functional>
#include <string_view>

#include "cli/run_cli.hpp"
#include "util/error.hpp"

namespace mbstorm::cli {

// Exit codes shared by every subcommand.
inline constexpr int kExitOk = 0;
inline constexpr int kExitFailed = 1;  // thresholds breached, findings present
inline constexpr int kExitUsage = 2;   // bad input, bad flags, unreachable target
// A run or fuzz campaign interrupted by a signal exits 128 + the signal's number, the shell's
// convention (130 for SIGINT, 143 for SIGTERM), after writing every report.
inline int exit_code_for_signal(int signal_number) {
    return 128 + signal_number;
}
// "SIGINT", "SIGTERM" (the two signals run and fuzz stop on).
inline const char* signal_name(int signal_number) {
    return signal_number == 2 ? "SIGINT" : signal_number == 15 ? "SIGTERM" : "a signal";
}

// The one place an Error becomes an exit code (issue #30). Every kind is something the user
// gives or controls (a flag, a file, a target, this machine), so each exits as bad input does;
// thresholds and findings (kExitFailed) and signals are results, not Errors.
int exit_code_for(const Error& error);

// Says "mbstorm <command>: <error's text>" on stderr, one such line per line of the text, and
// returns its exit code: how every subcommand stops on an Error.
int fail(std::string_view command, const Error& error);

// A plain refusal of the command line (a flag, a combination of flags): fail() with an
// InvalidInput error, so "mbstorm <command>: <message>" and kExitUsage.
int usage_error(std::string_view command, std::string_view message);

using Action = std::function<int()>;

void add_decode_command(CLI::App& app, Action& action);
void add_encode_command(CLI::App& app, Action& action);
void add_serve_command(CLI::App& app, Action& action);
void add_run_command(CLI::App& app, Action& action);
void add_fuzz_command(CLI::App& app, Action& action);
void add_replay_command(CLI::App& app, Action& action);
void add_read_command(CLI::App& app, Action& action);
void add_write_command(CLI::App& app, Action& action);
void add_merge_command(CLI::App& app, Action& action);
// Walks `app` when run: add it after every other subcommand.
void add_completion_command(CLI::App& app, Action& action);
// Every subcommand above, in the order --help lists them: the whole command line.
void add_all_commands(CLI::App& app, Action& action);

}  // namespace mbstorm::cli
