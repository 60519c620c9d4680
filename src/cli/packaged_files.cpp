#include "cli/packaged_files.hpp"

#include <filesystem>
#include <system_error>

namespace mbstorm::cli {
namespace fs = std::filesystem;

std::string packaged_dir(std::string_view what) {
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    if (!ec) {
        const fs::path installed = exe.parent_path().parent_path() / "share" / "mbstorm" / what;
        if (fs::is_directory(installed, ec)) return installed.lexically_normal().string();
    }
#ifdef MBSTORM_SOURCE_DIR
    // A binary run from its build folder (tests, a developer): the checkout's files.
    const fs::path source = fs::path(MBSTORM_SOURCE_DIR) / what;
    if (fs::is_directory(source, ec)) return source.string();
#endif
    return {};
}

std::string find_scenario(const std::string& arg) {
    std::error_code ec;
    if (fs::is_regular_file(arg, ec)) return arg;
    // A bare name only: a path that does not exist is the user's typo, not a packaged file.
    if (arg.empty() || arg.find('/') != std::string::npos) return {};
    const std::string dir = packaged_dir("scenarios");
    if (dir.empty()) return {};
    for (const fs::path& p : {fs::path(dir) / arg, fs::path(dir) / (arg + ".yaml")})
        if (fs::is_regular_file(p, ec)) return p.string();
    return {};
}

}  // namespace mbstorm::cli
