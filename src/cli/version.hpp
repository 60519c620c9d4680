// What `mbstorm --version` prints: the build (version, commit, compiler, build type), the
// io_uring features this kernel offers and the backend `run` and `serve` would use here (and
// why, when it is epoll), so a bug report says what ran where.
#pragma once

#include <string>

#include "cli/build_info.hpp"
#include "net/backend.hpp"
#include "net/features.hpp"

namespace mbstorm::cli {

// Lines without a final newline; the first is "mbstorm <version>" (what help2man reads).
// run_backend / serve_backend: what `--backend auto` picks for each (run needs provided-buffer
// rings, serve does not, so on a 5.6-5.18 kernel they differ).
std::string version_text(const BuildInfo& build, const net::Features& kernel,
                         const net::BackendDecision& run_backend,
                         const net::BackendDecision& serve_backend);

}  // namespace mbstorm::cli
