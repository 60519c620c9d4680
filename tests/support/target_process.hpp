// A child process (a server under test) whose stdout a test reads line by line, and the
// reference slave started through `mbstorm serve`.
#pragma once

#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <memory>
#include <string>
#include <thread>
#include <vector>

namespace mbstorm::test {

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

// Starts `mbstorm serve` on an ephemeral loopback port (plus `extra` arguments); returns
// "127.0.0.1:PORT", or "" when it did not come up.
inline std::string start_reference_slave(std::unique_ptr<Target>& server,
                                         std::vector<std::string> extra = {}) {
    std::vector<std::string> argv{MBSTORM_BINARY, "serve", "--listen",   "127.0.0.1:0",
                                  "--threads",    "1",     "--duration", "120s"};
    argv.insert(argv.end(), extra.begin(), extra.end());
    server = std::make_unique<Target>(argv);
    const std::string line = server->wait_for_line("listening on ");
    const auto at = line.find("listening on ");
    if (at == std::string::npos) return {};
    const auto rest = line.substr(at + 13);
    return rest.substr(0, rest.find(' '));
}

}  // namespace mbstorm::test
