// A Modbus slave scripted by a test, in a thread on a loopback port: the test says what it
// does with each connection's bytes, so a target's one odd behaviour is reproduced exactly.
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "../support/loopback_listener.hpp"

namespace mbstorm::test {

using SlaveBytes = std::vector<std::uint8_t>;

// A slave in a thread on a loopback port: `consume` takes each connection's bytes received so
// far, drops what it has acted on and sends its answers.
class ThreadSlave {
  public:
    using Consume = std::function<void(int fd, SlaveBytes& buffer)>;
    explicit ThreadSlave(Consume consume) : consume_(std::move(consume)) {
        fd_ = listen_on_loopback(1024, port_);  // the capacity tests open hundreds at once
        thread_ = std::thread([this] { serve(); });
    }
    ~ThreadSlave() {
        stop_ = true;
        thread_.join();
        ::close(fd_);
    }
    std::string endpoint() const { return "127.0.0.1:" + std::to_string(port_); }

  private:
    void serve() {
        std::vector<int> conns;
        std::vector<SlaveBytes> bufs;
        // Bounded in time, however busy (a fuzz run keeps it busy).
        const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(300);
        while (!stop_ && std::chrono::steady_clock::now() < end) {
            std::vector<pollfd> ps{{fd_, POLLIN, 0}};
            for (int c : conns) ps.push_back({c, POLLIN, 0});
            if (::poll(ps.data(), ps.size(), 20) <= 0) continue;
            // Only the connections polled above (a new one joins the next round).
            const std::size_t polled = conns.size();
            if (ps[0].revents & POLLIN) {
                conns.push_back(::accept(fd_, nullptr, nullptr));
                bufs.emplace_back();
            }
            for (std::size_t i = 0; i < polled; ++i) {
                if (!(ps[i + 1].revents & (POLLIN | POLLHUP))) continue;
                std::uint8_t b[512];
                const ssize_t n = ::recv(conns[i], b, sizeof b, 0);
                if (n <= 0) {
                    ::close(conns[i]);
                    conns.erase(conns.begin() + static_cast<std::ptrdiff_t>(i));
                    bufs.erase(bufs.begin() + static_cast<std::ptrdiff_t>(i));
                    break;
                }
                bufs[i].insert(bufs[i].end(), b, b + n);
                consume_(conns[i], bufs[i]);
            }
        }
        for (int c : conns) ::close(c);
    }
    Consume consume_;
    int fd_ = -1;
    std::uint16_t port_ = 0;
    std::atomic<bool> stop_{false};
    std::thread thread_;
};

inline void send_bytes(int fd, const SlaveBytes& b) {
    (void)!::send(fd, b.data(), b.size(), MSG_NOSIGNAL);
}

}  // namespace mbstorm::test
