#include "cli/version.hpp"

#include <fmt/format.h>

namespace mbstorm::cli {

namespace {

std::string io_uring_line(const net::Features& kernel) {
    std::string line =
        fmt::format("io_uring (kernel {}):", kernel.kernel.empty() ? "?" : kernel.kernel);
    if (!kernel.ring) return line + " unavailable (kernel too old, or io_uring blocked)";
    std::string missing;
    for (const net::NamedFeature& feature : net::named_features(kernel)) {
        (feature.offered ? line : missing).append(" ").append(feature.name);
    }
    if (!missing.empty()) line.append("; not offered:").append(missing);
    return line;
}

}  // namespace

std::string version_text(const BuildInfo& build, const net::Features& kernel) {
    return fmt::format("mbstorm {}\ncommit: {}\ncompiler: {}\nbuild type: {}\n{}", build.version,
                       build.commit, build.compiler, build.build_type, io_uring_line(kernel));
}

}  // namespace mbstorm::cli
