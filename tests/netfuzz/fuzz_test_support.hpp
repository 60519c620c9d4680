// Helpers for the fuzzer's end-to-end tests: start a target process (the reference slave via
// `mbstorm serve`, or a broken server from tests/tools) and run the mbstorm binary.
#pragma once

#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <sys/prctl.h>

#include <cerrno>
#include <set>

#include "../support/run_mbstorm.hpp"
#include "../support/target_process.hpp"

namespace mbstorm::test {

// The broken servers are built next to the test executables (build/tests/).
inline std::string tool_path(const std::string& name) {
    return (std::filesystem::path(MBSTORM_BINARY).parent_path() / "tests" / name).string();
}

// A broken server from tests/tools, restarted by its own supervisor after a crash.
inline std::string start_broken(Target*& target, const std::string& name) {
    target = new Target({tool_path(name), "--respawn", "--restart-delay-ms", "200"});
    const std::string line = target->wait_for_line("PORT ");
    return line.empty() ? std::string() : "127.0.0.1:" + line.substr(5);
}

inline std::string temp_dir(const std::string& name) {
    const auto dir = std::filesystem::temp_directory_path() /
                     ("mbstorm-netfuzz-" + name + "-" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir.string();
}

// broken_server_crash without a supervisor, on a fixed port below the kernel's ephemeral
// range, so a restart can bind the same port again and none of the fuzzer's own connects
// while the target is down can take it (a loopback self-connect would look like a target
// that answers). It ends by itself after `lifetime_s` even if the test dies first. `salt`
// keeps two servers of one test apart.
inline std::unique_ptr<Target> start_fixed_port_server(const std::string& tool, int& port,
                                                       int salt = 0, int lifetime_s = 300) {
    std::ifstream range("/proc/sys/net/ipv4/ip_local_port_range");
    int ephemeral_low = 32768;
    range >> ephemeral_low;
    const int high = std::max(ephemeral_low, 9024);
    const int low = std::max(1024, high - 8000);
    for (int attempt = 0; attempt < 40; ++attempt) {
        const int candidate =
            low + (static_cast<int>(::getpid()) * 13 + salt * 4001 + attempt * 997) % (high - low);
        auto server = std::make_unique<Target>(
            std::vector<std::string>{tool_path(tool), "--port", std::to_string(candidate),
                                     "--exit-after-s", std::to_string(lifetime_s)});
        // A port in use makes the server exit without printing its port.
        if (!server->wait_for_line("PORT ").empty()) {
            port = candidate;
            return server;
        }
    }
    return nullptr;
}

inline std::unique_ptr<Target> start_crash_server(int& port, int salt = 0, int lifetime_s = 300) {
    return start_fixed_port_server("broken_server_crash", port, salt, lifetime_s);
}

// Servers a fuzzer's --restart-cmd started in the background: their parent shell exits at
// once, so without a subreaper they would be re-parented to PID 1 (which in a container may
// never reap them). While this object lives, this test process adopts them instead, so it can
// stop and reap every one. Each server appends its pid to `pid_file` (--pid-file).
class RestartedServers {
  public:
    explicit RestartedServers(std::string pid_file) : pid_file_(std::move(pid_file)) {
        ::prctl(PR_SET_CHILD_SUBREAPER, 1);
    }
    ~RestartedServers() {
        stop_all();
        ::prctl(PR_SET_CHILD_SUBREAPER, 0);
    }
    RestartedServers(const RestartedServers&) = delete;
    RestartedServers& operator=(const RestartedServers&) = delete;

    std::vector<pid_t> pids() const {
        std::vector<pid_t> out;
        std::ifstream in(pid_file_);
        for (int pid = 0; in >> pid;)
            if (pid > 1) out.push_back(pid);
        return out;
    }
    // SIGKILL and reap each one (the ones that crashed are zombies already). True when none
    // is left.
    bool stop_all() {
        bool all_gone = true;
        for (pid_t pid : pids()) {
            if (reaped_.count(pid)) continue;
            ::kill(pid, SIGKILL);
            // While this process is their subreaper they stay our (zombie) children until
            // reaped here, so a pid from the file cannot have been reused by then.
            const pid_t waited = ::waitpid(pid, nullptr, 0);
            if (waited == pid || (waited < 0 && errno == ECHILD)) reaped_.insert(pid);
            if (::kill(pid, 0) == 0) all_gone = false;
        }
        return all_gone;
    }

  private:
    std::string pid_file_;
    std::set<pid_t> reaped_;
};

}  // namespace mbstorm::test
