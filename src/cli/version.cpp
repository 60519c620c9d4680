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

std::string backend_text(const net::BackendDecision& decision) {
    std::string text(net::backend_name(decision.backend));
    if (!decision.why.empty()) text += fmt::format(" ({})", decision.why);
    return text;
}

std::string backend_line(const net::BackendDecision& run, const net::BackendDecision& serve) {
    if (run.backend == serve.backend) return "backend: " + backend_text(run);
    return fmt::format("backend: run on {}, serve on {}", backend_text(run), backend_text(serve));
}

}  // namespace

std::string version_text(const BuildInfo& build, const net::Features& kernel,
                         const net::BackendDecision& run_backend,
                         const net::BackendDecision& serve_backend) {
    return fmt::format("mbstorm {}\ncommit: {}\ncompiler: {}\nbuild type: {}\n{}\n{}",
                       build.version, build.commit, build.compiler, build.build_type,
                       io_uring_line(kernel), backend_line(run_backend, serve_backend));
}

}  // namespace mbstorm::cli
