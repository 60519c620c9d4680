// CLI11 options that take durations ("2ms", "30s", "1m30s"), rates ("1%", "0.01") and real
// numbers within a range (never NaN or infinity).
#pragma once

#include <CLI/CLI.hpp>

#include <cstdint>
#include <string>

namespace mbstorm::cli {

// Adds an option whose value is a duration, stored in nanoseconds; a bad value is a usage
// error naming the accepted forms.
CLI::Option* add_duration_option(CLI::App* cmd, const std::string& name, std::uint64_t& ns,
                                 const std::string& description);

// Adds an option taking a fraction as "1%" or "0.01", stored as 0.01; must be within [0, 1].
CLI::Option* add_rate_option(CLI::App* cmd, const std::string& name, double& fraction,
                             const std::string& description);

// Adds an option taking a finite real number in [min, max], stored in `value`. A bad value is
// a usage error that states the range in words, e.g. "a number from 0 to 1,000,000,000".
CLI::Option* add_number_option(CLI::App* cmd, const std::string& name, double& value, double min,
                               double max, const std::string& description);

// Adds an option taking a whole number of at least `min` (a count; a limit whose 0 means none
// takes min 0). Signs, fractions and trailing text are usage errors.
CLI::Option* add_count_option(CLI::App* cmd, const std::string& name, std::uint64_t& value,
                              const std::string& description, std::uint64_t min = 1);

}  // namespace mbstorm::cli
