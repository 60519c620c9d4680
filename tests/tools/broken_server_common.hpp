// Skeleton of the deliberately broken Modbus TCP servers the fuzzer tests hunt: a small
// single-threaded poll() server that answers through the reference handler (slave/handler)
// except where a planted fault hook says otherwise. Each broken_server_*.cpp plants one fault.
//
// Usage: broken_server_X [--port P] [--respawn] [--restart-delay-ms N] [--pid-file F]
//                        [--exit-after-s N] [--one-connection]
// Prints "PORT <n>" once listening. With --respawn a supervisor restarts the server after it
// dies (as systemd or a PLC watchdog would), on the same port, after the restart delay.
// --pid-file appends the process id to F, so a test that starts servers in the background
// (a fuzzer's --restart-cmd) can stop every one; --exit-after-s bounds the lifetime of such a
// server in case the test itself dies before it can.
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "codec/bytes.hpp"
#include "codec/limits.hpp"
#include "slave/data_model.hpp"
#include "slave/handler.hpp"

namespace broken {

enum class Action { Default, Reply, Silent, StopServing, Close };

struct Client {
    int fd = -1;
    std::vector<std::uint8_t> in;
    bool stopped = false;  // a planted hang: never read or answer again
};

// What a broken server plants. on_frame sees each complete ADU first; `reply` is the ADU to
// send for Action::Reply.
struct Faults {
    Action (*on_frame)(const std::uint8_t* adu, std::size_t size, std::vector<std::uint8_t>& reply,
                       mbstorm::slave::DataModel& model) = nullptr;
    // Post-processes every normal reply ADU (e.g. to corrupt the transaction id).
    void (*on_reply)(const std::uint8_t* request, std::vector<std::uint8_t>& reply) = nullptr;
    bool drop_partial_header = false;  // framing bug: a header split across reads is lost
    // Framing bug: a read that leaves less than a header is taken for a bad frame, and the
    // connection closed (as pymodbus 3.0 does).
    bool close_on_partial_header = false;
    // A slow or busy target: bytes wait this long in its socket before it reads them.
    int read_delay_ms = 0;
    bool answer_any_protocol = false;  // answers frames with protocol id != 0
    // Serves one connection at a time (--one-connection), as many small devices and
    // libmodbus's simplest server loop do: the next waits in the listen backlog.
    bool one_connection = false;
};

inline void handle_default(const std::uint8_t* adu, std::size_t size,
                           std::vector<std::uint8_t>& reply, mbstorm::slave::DataModel& model) {
    std::uint8_t out[mbstorm::slave::kMinOutput];
    const auto r = mbstorm::slave::handle_request(mbstorm::codec::Bytes(adu + 7, size - 7), model,
                                                  mbstorm::codec::MutableBytes(out, sizeof out));
    reply.clear();
    if (r.outcome == mbstorm::slave::Outcome::NoResponse || r.size == 0) return;
    reply.assign(adu, adu + 7);
    reply[2] = reply[3] = 0;
    mbstorm::codec::store_be16(reply.data() + 4, static_cast<std::uint16_t>(r.size + 1));
    reply.insert(reply.end(), out, out + r.size);
}

inline void exception_reply(const std::uint8_t* adu, std::uint8_t code,
                            std::vector<std::uint8_t>& reply) {
    reply.assign(adu, adu + 7);
    reply[2] = reply[3] = 0;
    mbstorm::codec::store_be16(reply.data() + 4, 3);
    reply.push_back(static_cast<std::uint8_t>(adu[7] | 0x80));
    reply.push_back(code);
}

inline void send_all(int fd, const std::vector<std::uint8_t>& b) {
    std::size_t off = 0;
    while (off < b.size()) {
        const ssize_t n = ::send(fd, b.data() + off, b.size() - off, MSG_NOSIGNAL);
        if (n <= 0) {
            if (n < 0 && (errno == EAGAIN || errno == EINTR)) {
                pollfd p{fd, POLLOUT, 0};
                ::poll(&p, 1, 100);
                continue;
            }
            return;
        }
        off += static_cast<std::size_t>(n);
    }
}

// Returns false when the connection must be closed.
inline bool consume(Client& c, const Faults& f, mbstorm::slave::DataModel& model) {
    std::vector<std::uint8_t> reply, out;
    std::size_t pos = 0;
    while (!c.stopped && c.in.size() - pos >= 7) {
        const std::uint8_t* p = c.in.data() + pos;
        const std::uint16_t pid = mbstorm::codec::load_be16(p + 2);
        const std::uint16_t len = mbstorm::codec::load_be16(p + 4);
        if (len < 2 || len > 254) return false;
        if (c.in.size() - pos < 6u + len) break;
        const std::size_t size = 6u + len;
        pos += size;
        if (pid != 0 && !f.answer_any_protocol) continue;
        Action a = f.on_frame ? f.on_frame(p, size, reply, model) : Action::Default;
        if (a == Action::Default) {
            handle_default(p, size, reply, model);
            if (!reply.empty() && f.on_reply) f.on_reply(p, reply);
            a = Action::Reply;
        }
        if (a == Action::Close) return false;
        if (a == Action::StopServing) {
            c.stopped = true;
            break;
        }
        if (a == Action::Reply) out.insert(out.end(), reply.begin(), reply.end());
    }
    c.in.erase(c.in.begin(), c.in.begin() + static_cast<std::ptrdiff_t>(pos));
    if (!out.empty()) send_all(c.fd, out);
    return true;
}

inline int serve(int listen_fd, const Faults& f) {
    mbstorm::slave::DataModel model;
    std::vector<Client> clients;
    std::vector<pollfd> fds;
    std::uint8_t buf[8192];
    for (;;) {
        const bool full = f.one_connection && !clients.empty();
        fds.assign(1, pollfd{listen_fd, static_cast<short>(full ? 0 : POLLIN), 0});
        for (const Client& c : clients)
            fds.push_back(pollfd{c.fd, static_cast<short>(c.stopped ? 0 : POLLIN), 0});
        if (::poll(fds.data(), fds.size(), 1000) < 0 && errno != EINTR) return 1;
        if (f.read_delay_ms) ::usleep(static_cast<useconds_t>(f.read_delay_ms) * 1000);
        if (fds[0].revents & POLLIN) {
            for (;;) {
                const int fd = ::accept4(listen_fd, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
                if (fd < 0) break;
                int one = 1;
                ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
                clients.push_back(Client{fd, {}, false});
                if (f.one_connection) break;
            }
        }
        std::vector<Client> keep;
        for (std::size_t i = 0; i < clients.size(); ++i) {
            Client& c = clients[i];
            const short rev = i + 1 < fds.size() ? fds[i + 1].revents : 0;
            bool open = true;
            if (rev & (POLLIN | POLLHUP | POLLERR)) {
                const ssize_t n = ::recv(c.fd, buf, sizeof buf, 0);
                if (n == 0 || (n < 0 && errno != EAGAIN && errno != EINTR)) {
                    open = false;
                } else if (n > 0) {
                    // Planted framing bug: assumes a header always arrives in one read.
                    if (f.drop_partial_header && !c.in.empty() && c.in.size() < 7) c.in.clear();
                    c.in.insert(c.in.end(), buf, buf + n);
                    open = consume(c, f, model);
                    if (f.close_on_partial_header && !c.in.empty() && c.in.size() < 7) open = false;
                }
            }
            if (open)
                keep.push_back(std::move(c));
            else
                ::close(c.fd);
        }
        clients = std::move(keep);
    }
}

inline int listen_on(std::uint16_t port) {
    const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    int one = 1;
    ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 || ::listen(fd, 512) != 0)
        return -1;
    return fd;
}

inline std::uint16_t port_of(int fd) {
    sockaddr_in a{};
    socklen_t len = sizeof a;
    ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
    return ntohs(a.sin_port);
}

inline pid_t g_child = 0;
inline void forward_stop(int) {
    if (g_child > 0) {
        ::kill(g_child, SIGKILL);
        // Reap it: orphaned, it would stay a zombie where PID 1 does not reap (containers).
        ::waitpid(g_child, nullptr, 0);
    }
    _exit(0);
}

using ServeFn = int (*)(int listen_fd, const Faults& f);

// `serve_fn`: a server with its own loop (the multi-fault server) instead of serve().
inline int main_with(int argc, char** argv, const Faults& planted, ServeFn serve_fn = serve) {
    Faults f = planted;
    int port = 0, restart_delay_ms = 300, exit_after_s = 0;
    bool respawn = false;
    const char* pid_file = nullptr;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--port" && i + 1 < argc)
            port = std::atoi(argv[++i]);
        else if (a == "--respawn")
            respawn = true;
        else if (a == "--restart-delay-ms" && i + 1 < argc)
            restart_delay_ms = std::atoi(argv[++i]);
        else if (a == "--pid-file" && i + 1 < argc)
            pid_file = argv[++i];
        else if (a == "--exit-after-s" && i + 1 < argc)
            exit_after_s = std::atoi(argv[++i]);
        else if (a == "--one-connection")
            f.one_connection = true;
    }
    if (pid_file) {
        FILE* out = std::fopen(pid_file, "a");
        if (!out) return 2;
        std::fprintf(out, "%d\n", static_cast<int>(::getpid()));
        std::fclose(out);
    }
    // SIGALRM's default action ends the process (and, with --respawn, its child through
    // PR_SET_PDEATHSIG).
    if (exit_after_s > 0) ::alarm(static_cast<unsigned>(exit_after_s));
    rlimit no_core{0, 0};
    ::setrlimit(RLIMIT_CORE, &no_core);  // planted crashes leave no core files
    ::signal(SIGPIPE, SIG_IGN);
    if (!respawn) {
        const int fd = listen_on(static_cast<std::uint16_t>(port));
        if (fd < 0) return 2;
        std::printf("PORT %u\n", port_of(fd));
        std::fflush(stdout);
        return serve_fn(fd, f);
    }
    ::signal(SIGTERM, forward_stop);
    ::signal(SIGINT, forward_stop);
    bool announced = false;
    for (;;) {
        int fds[2];
        if (::pipe(fds) != 0) return 2;
        const pid_t child = ::fork();
        if (child == 0) {
            ::prctl(PR_SET_PDEATHSIG, SIGKILL);
            ::close(fds[0]);
            const int fd = listen_on(static_cast<std::uint16_t>(port));
            std::uint16_t p = fd < 0 ? 0 : port_of(fd);
            (void)!::write(fds[1], &p, sizeof p);
            ::close(fds[1]);
            if (fd < 0) _exit(2);
            _exit(serve_fn(fd, f));
        }
        g_child = child;
        ::close(fds[1]);
        std::uint16_t p = 0;
        if (::read(fds[0], &p, sizeof p) != sizeof p || p == 0) {
            ::close(fds[0]);
            ::usleep(100000);  // the port may still be in use: try again
            continue;
        }
        ::close(fds[0]);
        port = p;
        if (!announced) {
            std::printf("PORT %u\n", p);
            std::fflush(stdout);
            announced = true;
        }
        int status = 0;
        ::waitpid(child, &status, 0);
        ::usleep(static_cast<useconds_t>(restart_delay_ms) * 1000);
    }
}

}  // namespace broken
