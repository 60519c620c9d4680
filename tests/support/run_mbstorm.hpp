// Runs the built mbstorm binary and captures what it prints, for end-to-end CLI tests.
#pragma once

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

namespace mbstorm::test {

struct CommandResult {
    int exit_code = -1;
    std::string output;  // stdout and stderr together
};

inline CommandResult run_mbstorm(const std::string& args) {
    // Appended piecewise: g++ 12 warns falsely (-Warray-bounds) on `literal + string` chains.
    std::string cmd = MBSTORM_BINARY;
    cmd.append(" ").append(args).append(" 2>&1");
    CommandResult result;
    FILE* pipe = popen(cmd.c_str(), "r");
    if (!pipe) return result;
    std::array<char, 4096> buf{};
    std::size_t n;
    while ((n = fread(buf.data(), 1, buf.size(), pipe)) > 0) result.output.append(buf.data(), n);
    int status = pclose(pipe);
    result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return result;
}

}  // namespace mbstorm::test
