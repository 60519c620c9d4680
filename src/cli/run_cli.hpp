// The command line's entry point, kept free of CLI11 so that main() compiles quickly.
#pragma once

namespace mbstorm::cli {

// Parses argv and runs the chosen subcommand; returns the process exit code.
int run_cli(int argc, char** argv);

}  // namespace mbstorm::cli
