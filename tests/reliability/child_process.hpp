// Runs the built mbstorm binary as a child process whose output (stdout and stderr) can be read
// line by line while it runs, signalled, and waited for with a bound.
#pragma once

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <string>
#include <vector>

namespace mbstorm::test {

class ChildProcess {
  public:
    // `nofile`: when not 0, the child's RLIMIT_NOFILE, soft and hard (it cannot raise it).
    explicit ChildProcess(const std::vector<std::string>& args, rlim_t nofile = 0) {
        int fds[2];
        if (::pipe2(fds, O_CLOEXEC) != 0) return;
        pid_ = ::fork();
        if (pid_ == 0) {
            if (nofile != 0) {
                const rlimit limit{nofile, nofile};
                if (::setrlimit(RLIMIT_NOFILE, &limit) != 0) ::_exit(126);
            }
            ::dup2(fds[1], 1);
            ::dup2(fds[1], 2);
            std::vector<char*> argv;
            std::string binary = MBSTORM_BINARY;
            argv.push_back(binary.data());
            std::vector<std::string> copy = args;
            for (auto& a : copy) argv.push_back(a.data());
            argv.push_back(nullptr);
            ::execv(binary.c_str(), argv.data());
            ::_exit(127);
        }
        ::close(fds[1]);
        out_fd_ = fds[0];
    }
    ~ChildProcess() {
        if (pid_ > 0 && !exited_) {
            ::kill(pid_, SIGKILL);
            ::waitpid(pid_, nullptr, 0);
        }
        if (out_fd_ >= 0) ::close(out_fd_);
    }
    ChildProcess(const ChildProcess&) = delete;
    ChildProcess& operator=(const ChildProcess&) = delete;

    pid_t pid() const { return pid_; }
    const std::string& output() const { return output_; }

    // Reads until the output holds `text` (true) or `timeout_ms` pass (false).
    bool wait_for_output(const std::string& text, int timeout_ms = 10000) {
        const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
        while (output_.find(text) == std::string::npos) {
            const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
                until - std::chrono::steady_clock::now());
            if (left.count() <= 0 || !read_some(static_cast<int>(left.count()))) return false;
        }
        return true;
    }
    void signal(int sig) { ::kill(pid_, sig); }
    // The exit code (128 + signal when killed by one), or -1 if it is still running after
    // `timeout_ms` (then it is killed).
    int wait(int timeout_ms = 20000) {
        const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
        int status = 0;
        for (;;) {
            read_some(20);
            const pid_t r = ::waitpid(pid_, &status, WNOHANG);
            if (r == pid_) break;
            if (std::chrono::steady_clock::now() > until) return -1;
        }
        exited_ = true;
        while (read_some(50)) {
        }
        if (WIFEXITED(status)) return WEXITSTATUS(status);
        return WIFSIGNALED(status) ? 128 + WTERMSIG(status) : -1;
    }
    // Resident memory of the child in KiB (VmRSS), 0 when unknown.
    long rss_kib() const {
        FILE* f = std::fopen(("/proc/" + std::to_string(pid_) + "/status").c_str(), "r");
        if (!f) return 0;
        char line[256];
        long kib = 0;
        while (std::fgets(line, sizeof line, f))
            if (std::sscanf(line, "VmRSS: %ld kB", &kib) == 1) break;
        std::fclose(f);
        return kib;
    }

  private:
    bool read_some(int timeout_ms) {
        pollfd p{out_fd_, POLLIN, 0};
        if (::poll(&p, 1, timeout_ms) != 1) return false;
        char buf[4096];
        const ssize_t n = ::read(out_fd_, buf, sizeof buf);
        if (n <= 0) return false;
        output_.append(buf, static_cast<std::size_t>(n));
        return true;
    }

    pid_t pid_ = -1;
    int out_fd_ = -1;
    bool exited_ = false;
    std::string output_;
};

}  // namespace mbstorm::test
