// What `mbstorm --version` prints: the build (version, commit, compiler, build type) and the
// io_uring features this kernel offers, so a bug report says what ran where.
#pragma once

#include <string>

#include "cli/build_info.hpp"
#include "net/features.hpp"

namespace mbstorm::cli {

// Lines without a final newline; the first is "mbstorm <version>" (what help2man reads).
std::string version_text(const BuildInfo& build, const net::Features& kernel);

}  // namespace mbstorm::cli
