// Old spellings of renamed flags (issue #29, one meaning per flag): they keep working, hidden
// from --help and from completion, and each use says once on stderr which spelling to use.
#pragma once

#include <CLI/CLI.hpp>

#include <string>

namespace mbstorm::cli {

// Prints "mbstorm <command>: <old> is deprecated, use <current>" on stderr.
void warn_deprecated(const std::string& command, const std::string& old_name,
                     const std::string& current_name);

// Adds `old_name` (one spelling, "-q" or "--count") as a hidden option filling `variable`,
// the variable of `current_name`; the caller adds the same checks as the current option's.
// Hidden options are in group "": the test of one meaning per flag skips them, as their
// meaning is the old one on purpose.
template <typename T>
CLI::Option* add_deprecated_option(CLI::App* cmd, const std::string& old_name,
                                   const std::string& current_name, T& variable) {
    return cmd->add_option(old_name, variable, "deprecated: " + current_name)
        ->group("")
        ->each([command = cmd->get_name(), old_name, current_name](const std::string&) {
            warn_deprecated(command, old_name, current_name);
        });
}

}  // namespace mbstorm::cli
