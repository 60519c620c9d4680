#include "netfuzz/restart_command.hpp"

#include <spawn.h>
#include <sys/wait.h>

#include <cerrno>
#include <cstring>
#include <vector>

extern char** environ;

namespace mbstorm::netfuzz {
namespace {

// Commands that were still running when their RestartCommand went away (single-threaded
// campaign: no lock needed).
std::vector<pid_t>& left_running() {
    static std::vector<pid_t> pids;
    return pids;
}

void reap_left_running() {
    auto& pids = left_running();
    std::erase_if(pids, [](pid_t pid) {
        const pid_t r = ::waitpid(pid, nullptr, WNOHANG);
        return r == pid || (r < 0 && errno == ECHILD);
    });
}

}  // namespace

bool RestartCommand::start(const std::string& command, std::string& error) {
    reap_left_running();
    const char* argv[] = {"sh", "-c", command.c_str(), nullptr};
    const int rc =
        ::posix_spawn(&pid_, "/bin/sh", nullptr, nullptr, const_cast<char**>(argv), environ);
    if (rc != 0) {
        pid_ = -1;
        error = std::string("cannot run --restart-cmd: ") + std::strerror(rc);
        return false;
    }
    return true;
}

bool RestartCommand::returned() {
    if (pid_ < 0) return true;
    const pid_t r = ::waitpid(pid_, nullptr, WNOHANG);
    if (r == pid_ || (r < 0 && errno == ECHILD)) {
        pid_ = -1;
        return true;
    }
    return false;
}

RestartCommand::~RestartCommand() {
    if (pid_ >= 0 && !returned()) left_running().push_back(pid_);
}

}  // namespace mbstorm::netfuzz
