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

#include "../support/run_mbstorm.hpp"

namespace mbstorm::test {

// The broken servers are built next to the test executables (build/tests/).
inline std::string tool_path(const std::string& name) {
    return (std::filesystem::path(MBSTORM_BINARY).parent_path() / "tests" / name).string();
}

// A child process whose stdout we read line by line; stopped (SIGTERM, then SIGKILL) on exit.
class Target {
  public:
    explicit Target(std::vector<std::string> argv) {
        int fds[2];
        if (::pipe(fds) != 0) return;
        pid_ = ::fork();
        if (pid_ == 0) {
            ::dup2(fds[1], 1);
            ::close(fds[0]);
            ::close(fds[1]);
            std::vector<char*> args;
            for (auto& a : argv) args.push_back(a.data());
            args.push_back(nullptr);
            ::execv(args[0], args.data());
            _exit(127);
        }
        ::close(fds[1]);
        out_ = fds[0];
    }
    ~Target() {
        if (pid_ > 0) {
            ::kill(pid_, SIGTERM);
            for (int i = 0; i < 100; ++i) {
                if (::waitpid(pid_, nullptr, WNOHANG) == pid_) {
                    pid_ = 0;
                    break;
                }
                std::this_thread::sleep_for(std::chrono::milliseconds(20));
            }
            if (pid_ > 0) {
                ::kill(pid_, SIGKILL);
                ::waitpid(pid_, nullptr, 0);
            }
        }
        if (out_ >= 0) ::close(out_);
    }
    Target(const Target&) = delete;
    Target& operator=(const Target&) = delete;

    // Reads until a line containing `marker` appears (or 10 s pass); returns that line.
    std::string wait_for_line(const std::string& marker) {
        const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
        while (std::chrono::steady_clock::now() < deadline) {
            const auto nl = buffer_.find('\n');
            if (nl != std::string::npos) {
                std::string line = buffer_.substr(0, nl);
                buffer_.erase(0, nl + 1);
                if (line.find(marker) != std::string::npos) return line;
                continue;
            }
            pollfd p{out_, POLLIN, 0};
            if (::poll(&p, 1, 100) <= 0) continue;
            char buf[512];
            const ssize_t n = ::read(out_, buf, sizeof buf);
            if (n <= 0) break;
            buffer_.append(buf, static_cast<std::size_t>(n));
        }
        return {};
    }

  private:
    pid_t pid_ = -1;
    int out_ = -1;
    std::string buffer_;
};

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
inline std::unique_ptr<Target> start_crash_server(int& port, int salt = 0, int lifetime_s = 300) {
    std::ifstream range("/proc/sys/net/ipv4/ip_local_port_range");
    int ephemeral_low = 32768;
    range >> ephemeral_low;
    const int high = std::max(ephemeral_low, 9024);
    const int low = std::max(1024, high - 8000);
    for (int attempt = 0; attempt < 40; ++attempt) {
        const int candidate =
            low + (static_cast<int>(::getpid()) * 13 + salt * 4001 + attempt * 997) % (high - low);
        auto server = std::make_unique<Target>(std::vector<std::string>{
            tool_path("broken_server_crash"), "--port", std::to_string(candidate), "--exit-after-s",
            std::to_string(lifetime_s)});
        // A port in use makes the server exit without printing its port.
        if (!server->wait_for_line("PORT ").empty()) {
            port = candidate;
            return server;
        }
    }
    return nullptr;
}

}  // namespace mbstorm::test
