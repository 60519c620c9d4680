// A deliberately hostile Modbus TCP target on an ephemeral loopback port, for the engine's
// attack tests: it reads FC03 requests (12 bytes each) and answers each the way its Mode says.
// One thread, poll(), any number of connections; stops (closing everything) on destruction or
// on kill().
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cstdint>
#include <random>
#include <thread>
#include <vector>

namespace mbstorm::test {

class HostileTarget {
  public:
    enum class Mode {
        Honest,            // a correct answer
        Silent,            // reads and never answers
        Garbage,           // random bytes instead of an answer
        LengthFFFF,        // an MBAP header announcing 0xFFFF bytes
        WrongId,           // the right answer under another transaction id
        Duplicate,         // every answer twice
        CloseAfterAnswer,  // a correct answer, then the connection is closed
        AllExceptions,     // exception 04 to everything
    };

    explicit HostileTarget(Mode mode, std::uint16_t port = 0) : mode_(mode) {
        listen_fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
        const int one = 1;
        ::setsockopt(listen_fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
        sockaddr_in addr{};
        addr.sin_family = AF_INET;
        addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        addr.sin_port = htons(port);
        bound_ = ::bind(listen_fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0 &&
                 ::listen(listen_fd_, 64) == 0;
        socklen_t len = sizeof addr;
        ::getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len);
        port_ = ntohs(addr.sin_port);
        thread_ = std::thread([this] { serve(); });
    }
    ~HostileTarget() { kill(); }
    HostileTarget(const HostileTarget&) = delete;
    HostileTarget& operator=(const HostileTarget&) = delete;

    bool ok() const { return bound_; }
    std::uint16_t port() const { return port_; }
    std::uint64_t requests() const { return requests_.load(); }
    // Stops listening and closes every connection, like a killed process.
    void kill() {
        stop_ = true;
        if (thread_.joinable()) thread_.join();
        if (listen_fd_ >= 0) ::close(listen_fd_);
        listen_fd_ = -1;
    }

  private:
    struct Peer {
        int fd;
        std::vector<std::uint8_t> in;
    };

    void serve() {
        std::vector<Peer> peers;
        std::mt19937 rng(12345);
        while (!stop_) {
            std::vector<pollfd> fds{{listen_fd_, POLLIN, 0}};
            for (auto& p : peers) fds.push_back({p.fd, POLLIN, 0});
            if (::poll(fds.data(), fds.size(), 20) <= 0) continue;
            if (fds[0].revents & POLLIN) {
                const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
                if (fd >= 0) peers.push_back({fd, {}});
            }
            for (std::size_t i = 1; i < fds.size(); ++i) {
                if (!(fds[i].revents & (POLLIN | POLLHUP | POLLERR))) continue;
                Peer& p = peers[i - 1];
                std::uint8_t buf[4096];
                const ssize_t n = ::recv(p.fd, buf, sizeof buf, 0);
                bool close_it = n <= 0;
                if (n > 0) {
                    p.in.insert(p.in.end(), buf, buf + n);
                    close_it = !answer(p, rng);
                }
                if (close_it) {
                    ::close(p.fd);
                    p.fd = -1;
                }
            }
            std::erase_if(peers, [](const Peer& p) { return p.fd < 0; });
        }
        for (auto& p : peers) ::close(p.fd);
    }

    // False: close the connection.
    bool answer(Peer& p, std::mt19937& rng) {
        std::vector<std::uint8_t> out;
        std::size_t at = 0;
        bool keep = true;
        while (p.in.size() - at >= 12 && keep) {
            const std::uint8_t* r = p.in.data() + at;
            at += 12;
            ++requests_;
            const std::uint16_t quantity = static_cast<std::uint16_t>(r[10] << 8 | r[11]);
            switch (mode_) {
                case Mode::Honest:
                    append_answer(out, r[0], r[1], r[6], quantity);
                    break;
                case Mode::Silent:
                    break;
                case Mode::Garbage:
                    for (int i = 0; i < 64; ++i) out.push_back(static_cast<std::uint8_t>(rng()));
                    out[out.size() - 64 + 4] = 0x7F;  // a length no frame can have
                    break;
                case Mode::LengthFFFF:
                    out.insert(out.end(), {r[0], r[1], 0, 0, 0xFF, 0xFF, r[6], 3, 0});
                    break;
                case Mode::WrongId:
                    append_answer(out, static_cast<std::uint8_t>(r[0] ^ 0x40), r[1], r[6],
                                  quantity);
                    break;
                case Mode::Duplicate:
                    append_answer(out, r[0], r[1], r[6], quantity);
                    append_answer(out, r[0], r[1], r[6], quantity);
                    break;
                case Mode::CloseAfterAnswer:
                    append_answer(out, r[0], r[1], r[6], quantity);
                    keep = false;
                    break;
                case Mode::AllExceptions:
                    out.insert(out.end(), {r[0], r[1], 0, 0, 0, 3, r[6], 0x83, 0x04});
                    break;
            }
        }
        p.in.erase(p.in.begin(), p.in.begin() + static_cast<std::ptrdiff_t>(at));
        if (!out.empty() && ::send(p.fd, out.data(), out.size(), MSG_NOSIGNAL) < 0) return false;
        return keep;
    }

    static void append_answer(std::vector<std::uint8_t>& out, std::uint8_t tid_hi,
                              std::uint8_t tid_lo, std::uint8_t unit, std::uint16_t quantity) {
        const std::uint16_t length = static_cast<std::uint16_t>(3 + 2 * quantity);
        out.insert(out.end(), {tid_hi, tid_lo, 0, 0, static_cast<std::uint8_t>(length >> 8),
                               static_cast<std::uint8_t>(length), unit, 0x03,
                               static_cast<std::uint8_t>(2 * quantity)});
        out.insert(out.end(), 2u * quantity, 0);
    }

    Mode mode_;
    int listen_fd_ = -1;
    bool bound_ = false;
    std::uint16_t port_ = 0;
    std::atomic<bool> stop_{false};
    std::atomic<std::uint64_t> requests_{0};
    std::thread thread_;
};

// A loopback address where connects hang, like a host that drops SYNs: a listener that never
// accepts, its backlog filled by connections of its own.
class HangingListener {
  public:
    HangingListener() {
        fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
        sockaddr_in addr{};
        addr.sin_family = AF_INET;
        addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        ::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr);
        ::listen(fd_, 0);
        socklen_t len = sizeof addr;
        ::getsockname(fd_, reinterpret_cast<sockaddr*>(&addr), &len);
        port_ = ntohs(addr.sin_port);
        // Backlog 0 still queues one connection; two more make sure the queue is full.
        for (int i = 0; i < 3; ++i) {
            const int c = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
            ::connect(c, reinterpret_cast<sockaddr*>(&addr), sizeof addr);
            fillers_.push_back(c);
        }
        ::usleep(50'000);  // the handshakes of the fillers complete
    }
    ~HangingListener() {
        for (int c : fillers_) ::close(c);
        ::close(fd_);
    }
    std::uint16_t port() const { return port_; }

  private:
    int fd_ = -1;
    std::uint16_t port_ = 0;
    std::vector<int> fillers_;
};

}  // namespace mbstorm::test
