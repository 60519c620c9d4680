// The EXAMPLES and EXIT STATUS sections of every subcommand's --help (and so of its man page:
// help2man makes a section of each "Heading:" paragraph), in one place.
#pragma once

#include <CLI/CLI.hpp>

#include <string>

namespace mbstorm::cli {

// Sets the footer of each subcommand of `app` that has one written; `scenarios_dir` is where
// the packaged scenarios are (named in run's examples).
void add_help_footers(CLI::App& app, const std::string& scenarios_dir);

}  // namespace mbstorm::cli
