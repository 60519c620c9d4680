#include "cli/deprecated_option.hpp"

#include <fmt/format.h>

#include <cstdio>

namespace mbstorm::cli {

void warn_deprecated(const std::string& command, const std::string& old_name,
                     const std::string& current_name) {
    fmt::print(stderr, "mbstorm {}: {} is deprecated, use {}\n", command, old_name, current_name);
}

}  // namespace mbstorm::cli
