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

// `limit_seconds` > 0 bounds the run from outside (timeout(1): exit 124 when it hits), so a
// stuck command fails its test instead of blocking the suite.
inline CommandResult run_mbstorm(const std::string& args, int limit_seconds = 0) {
    // Appended piecewise: g++ 12 warns falsely (-Warray-bounds) on `literal + string` chains.
    std::string cmd;
    if (limit_seconds > 0)
        cmd.append("timeout -k 10 ").append(std::to_string(limit_seconds)).append(" ");
    cmd.append(MBSTORM_BINARY);
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
