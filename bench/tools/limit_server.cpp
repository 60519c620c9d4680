// The floor for a Modbus TCP slave on this machine: single-threaded epoll, every 12-byte
// request answered with one canned 29-byte FC03 x10 response, all answers to one read() in
// one write(). No parsing, no data model: whatever a real server costs beyond this is its own.
//
//   limit_server [--port N] [--seconds S]     prints "PORT <n>" once listening
#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <signal.h>
#include <sys/epoll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace {

constexpr std::size_t kRequest = 12;
constexpr std::size_t kResponse = 29;
constexpr std::size_t kReadSize = 64 * 1024;

struct Conn {
    int fd = -1;
    std::size_t partial = 0;          // bytes of an incomplete request carried over
    unsigned char carry[2] = {0, 0};  // its transaction id bytes, where they arrived
    std::vector<unsigned char> out;   // unsent answers (only when the socket was full)
    std::size_t out_off = 0;
};

volatile sig_atomic_t g_stop = 0;

}  // namespace

int main(int argc, char** argv) {
    int port = 0;
    double seconds = 0;
    for (int i = 1; i + 1 < argc; i += 2) {
        std::string a = argv[i];
        if (a == "--port") port = std::atoi(argv[i + 1]);
        if (a == "--seconds") seconds = std::atof(argv[i + 1]);
    }
    signal(SIGPIPE, SIG_IGN);
    signal(SIGTERM, [](int) { g_stop = 1; });
    signal(SIGINT, [](int) { g_stop = 1; });

    int lfd = socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK, 0);
    int one = 1;
    setsockopt(lfd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    addr.sin_port = htons(static_cast<uint16_t>(port));
    if (bind(lfd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 || listen(lfd, 4096) != 0) {
        std::perror("limit_server: listen");
        return 1;
    }
    socklen_t len = sizeof addr;
    getsockname(lfd, reinterpret_cast<sockaddr*>(&addr), &len);
    std::printf("PORT %u\n", ntohs(addr.sin_port));
    std::fflush(stdout);

    int ep = epoll_create1(0);
    epoll_event ev{};
    ev.events = EPOLLIN;
    ev.data.u64 = ~0ull;
    epoll_ctl(ep, EPOLL_CTL_ADD, lfd, &ev);

    // The canned answer; the output buffer is filled with copies of it once.
    const unsigned char canned[kResponse] = {0, 1, 0, 0, 0, 23, 1, 3, 20};
    std::vector<unsigned char> answers((kReadSize / kRequest + 1) * kResponse);
    for (std::size_t i = 0; i + kResponse <= answers.size(); i += kResponse)
        std::memcpy(answers.data() + i, canned, kResponse);
    std::vector<unsigned char> in(kReadSize);
    std::vector<Conn> conns;
    const auto deadline = std::chrono::steady_clock::now() +
                          std::chrono::milliseconds(static_cast<long>(seconds * 1000));
    epoll_event events[256];
    while (!g_stop) {
        if (seconds > 0 && std::chrono::steady_clock::now() >= deadline) break;
        int n = epoll_wait(ep, events, 256, 200);
        for (int i = 0; i < n; ++i) {
            if (events[i].data.u64 == ~0ull) {
                for (;;) {
                    int fd = accept4(lfd, nullptr, nullptr, SOCK_NONBLOCK);
                    if (fd < 0) break;
                    setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
                    if (static_cast<std::size_t>(fd) >= conns.size()) conns.resize(fd + 1);
                    conns[fd] = Conn();
                    conns[fd].fd = fd;
                    epoll_event cev{};
                    cev.events = EPOLLIN;
                    cev.data.u64 = static_cast<std::uint64_t>(fd);
                    epoll_ctl(ep, EPOLL_CTL_ADD, fd, &cev);
                }
                continue;
            }
            Conn& c = conns[events[i].data.u64];
            if (!c.out.empty()) {  // finish a blocked write before reading more
                ssize_t w = write(c.fd, c.out.data() + c.out_off, c.out.size() - c.out_off);
                if (w > 0) c.out_off += static_cast<std::size_t>(w);
                if (c.out_off == c.out.size()) {
                    c.out.clear();
                    c.out_off = 0;
                    epoll_event cev{};
                    cev.events = EPOLLIN;
                    cev.data.u64 = static_cast<std::uint64_t>(c.fd);
                    epoll_ctl(ep, EPOLL_CTL_MOD, c.fd, &cev);
                }
                continue;
            }
            ssize_t r = read(c.fd, in.data(), in.size());
            if (r <= 0) {
                if (r < 0 && errno == EAGAIN) continue;
                close(c.fd);
                c.fd = -1;
                continue;
            }
            // Echo each request's transaction id so that clients matching responses by id
            // (as the Messaging Implementation Guide requires) can run against it; that copy
            // of two bytes per answer is the only per-request work.
            const std::size_t got = static_cast<std::size_t>(r);
            std::size_t count = 0;
            std::size_t pos = 0;
            if (c.partial) {
                for (std::size_t k = c.partial; k < 2 && pos < got; ++k) c.carry[k] = in[pos++];
                std::size_t need = kRequest - c.partial;
                if (got >= need) {
                    answers[0] = c.carry[0];
                    answers[1] = c.carry[1];
                    count = 1;
                    pos = need;
                    c.partial = 0;
                } else {
                    c.partial += got;
                    continue;
                }
            }
            for (; pos + kRequest <= got; pos += kRequest, ++count) {
                answers[count * kResponse] = in[pos];
                answers[count * kResponse + 1] = in[pos + 1];
            }
            if (pos < got) {
                c.partial = got - pos;
                c.carry[0] = in[pos];
                if (c.partial > 1) c.carry[1] = in[pos + 1];
            }
            if (count == 0) continue;
            std::size_t bytes = count * kResponse;
            ssize_t w = write(c.fd, answers.data(), bytes);
            if (w < 0) w = 0;
            if (static_cast<std::size_t>(w) < bytes) {
                c.out.assign(answers.data() + w, answers.data() + bytes);
                c.out_off = 0;
                epoll_event cev{};
                cev.events = EPOLLOUT;
                cev.data.u64 = static_cast<std::uint64_t>(c.fd);
                epoll_ctl(ep, EPOLL_CTL_MOD, c.fd, &cev);
            }
        }
    }
    for (auto& c : conns)
        if (c.fd >= 0) close(c.fd);
    close(lfd);
    return 0;
}
