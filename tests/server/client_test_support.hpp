// Plain blocking-socket client for the server tests (no io_uring, no codec: bytes by hand).
#pragma once

#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstdint>
#include <string>
#include <vector>

#include "net/socket.hpp"
#include "server/server.hpp"

namespace mbstorm::test {

inline constexpr int kTimeoutMs = 10000;  // generous: a busy 2-core machine

// FC03 read holding registers.
inline std::vector<std::uint8_t> read_holding(std::uint16_t tid, std::uint8_t unit,
                                              std::uint16_t address, std::uint16_t quantity) {
    return {static_cast<std::uint8_t>(tid >> 8),
            static_cast<std::uint8_t>(tid),
            0,
            0,
            0,
            6,
            unit,
            3,
            static_cast<std::uint8_t>(address >> 8),
            static_cast<std::uint8_t>(address),
            static_cast<std::uint8_t>(quantity >> 8),
            static_cast<std::uint8_t>(quantity)};
}

// Bytes of a response to read_holding(quantity).
inline std::size_t read_holding_response_size(std::uint16_t quantity) {
    return 7 + 2 + 2u * quantity;
}

class Client {
  public:
    // Creates the socket now and connects later with connect() (tests that need the
    // descriptor before the process runs out of them).
    struct DeferConnect {};

    // rcvbuf > 0: a small receive buffer, set before connecting (backpressure tests).
    explicit Client(const server::Server& srv, const std::string& host = "127.0.0.1",
                    int rcvbuf = 0)
        : Client(DeferConnect{}, host) {
        if (rcvbuf > 0) ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &rcvbuf, sizeof rcvbuf);
        connect(srv);
    }
    explicit Client(DeferConnect, const std::string& host = "127.0.0.1") {
        ep_ = *net::parse_endpoint(host.find(':') != std::string::npos ? "[" + host + "]:0"
                                                                       : host + ":0");
        fd_ = ::socket(ep_.family(), SOCK_STREAM | SOCK_CLOEXEC, 0);
    }
    // False (and the socket closed) when the connection fails.
    bool connect(const server::Server& srv) {
        ep_.set_port(srv.port());
        if (fd_ >= 0 && ::connect(fd_, ep_.sa(), ep_.len) == 0) return true;
        if (fd_ >= 0) ::close(fd_);
        fd_ = -1;
        return false;
    }
    ~Client() {
        if (fd_ >= 0) ::close(fd_);
    }
    Client(const Client&) = delete;
    Client& operator=(const Client&) = delete;
    Client(Client&& o) noexcept : ep_(o.ep_), fd_(o.fd_) { o.fd_ = -1; }

    bool ok() const { return fd_ >= 0; }
    int fd() const { return fd_; }

    bool send_all(const std::uint8_t* p, std::size_t n) {
        while (n > 0) {
            ssize_t r = ::send(fd_, p, n, MSG_NOSIGNAL);
            if (r <= 0) return false;
            p += r;
            n -= static_cast<std::size_t>(r);
        }
        return true;
    }
    bool send_all(const std::vector<std::uint8_t>& v) { return send_all(v.data(), v.size()); }

    // Reads exactly n bytes; false on timeout, error or EOF.
    bool recv_exact(std::uint8_t* p, std::size_t n, int timeout_ms = kTimeoutMs) {
        while (n > 0) {
            if (!wait_readable(timeout_ms)) return false;
            ssize_t r = ::recv(fd_, p, n, 0);
            if (r <= 0) return false;
            p += r;
            n -= static_cast<std::size_t>(r);
        }
        return true;
    }
    std::vector<std::uint8_t> recv_n(std::size_t n, int timeout_ms = kTimeoutMs) {
        std::vector<std::uint8_t> v(n);
        if (!recv_exact(v.data(), n, timeout_ms)) v.clear();
        return v;
    }
    // True when the server closes the connection (EOF or reset) within the timeout.
    bool closed_by_peer(int timeout_ms = kTimeoutMs) {
        std::uint8_t buf[4096];
        for (;;) {
            if (!wait_readable(timeout_ms)) return false;
            ssize_t r = ::recv(fd_, buf, sizeof buf, 0);
            if (r <= 0) return true;
        }
    }
    // True when nothing arrives within `ms`.
    bool silent_for(int ms) { return !wait_readable(ms); }

  private:
    bool wait_readable(int timeout_ms) {
        pollfd p{fd_, POLLIN, 0};
        return ::poll(&p, 1, timeout_ms) == 1;
    }
    net::Endpoint ep_;
    int fd_ = -1;
};

// Polls `pred` until it holds or ~10 s pass.
template <class Pred>
bool eventually(Pred pred) {
    for (int i = 0; i < 1000; ++i) {
        if (pred()) return true;
        ::usleep(10000);
    }
    return pred();
}

inline server::ServerConfig test_config() {
    server::ServerConfig c;
    c.listen = "127.0.0.1:0";
    c.threads = 1;
    return c;
}

}  // namespace mbstorm::test
