// What this binary is: its version (CMake's project(VERSION), the one place it is written),
// the git commit it was built from and how it was built. Defined in a source file that
// cmake/build_info.cmake writes at build time.
#pragma once

namespace mbstorm::cli {

struct BuildInfo {
    const char* version;     // project(VERSION), e.g. "1.2.3"
    const char* commit;      // `git describe --always --dirty`, "unknown" outside a checkout
    const char* compiler;    // "GNU 12.2.0"
    const char* build_type;  // "Release"
};

const BuildInfo& build_info() noexcept;

}  // namespace mbstorm::cli
