#include "netfuzz/restart_command.hpp"

#include <signal.h>
#include <spawn.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

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

Error RestartCommand::start(const std::string& command) {
    reap_left_running();
    if (own_group_) return start_owned(command);
    const char* argv[] = {"sh", "-c", command.c_str(), nullptr};
    const int rc =
        ::posix_spawn(&pid_, "/bin/sh", nullptr, nullptr, const_cast<char**>(argv), environ);
    if (rc != 0) {
        pid_ = -1;
        return Error(ErrorCode::Io, std::string("cannot run --restart-cmd: ") + std::strerror(rc));
    }
    return Error::none();
}

// The target of --target-cmd: a process group of its own (stop() ends all of it), killed
// with mbstorm however mbstorm ends, its stdout on mbstorm's stderr (stdout may carry a
// report).
Error RestartCommand::start_owned(const std::string& command) {
    const pid_t parent = ::getpid();
    pid_ = ::fork();
    if (pid_ < 0)
        return Error(ErrorCode::Io,
                     std::string("cannot run --target-cmd: ") + std::strerror(errno));
    if (pid_ == 0) {
        ::setpgid(0, 0);
        ::prctl(PR_SET_PDEATHSIG, SIGKILL);
        if (::getppid() != parent) ::_exit(127);  // mbstorm is gone already
        ::dup2(2, 1);
        ::execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
        ::_exit(127);
    }
    return Error::none();
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

void RestartCommand::stop() {
    if (pid_ < 0 || returned()) return;
    const pid_t target = own_group_ ? -pid_ : pid_;
    ::kill(target, SIGTERM);
    for (int i = 0; i < 100 && !returned(); ++i) ::usleep(10000);
    if (pid_ >= 0) {
        ::kill(target, SIGKILL);
        ::waitpid(pid_, nullptr, 0);
        pid_ = -1;
    }
    if (own_group_) ::kill(target, SIGKILL);  // what sh started and left behind
}

RestartCommand::~RestartCommand() {
    if (pid_ >= 0 && !returned()) left_running().push_back(pid_);
}

}  // namespace mbstorm::netfuzz
