// A Modbus TCP server with many planted bugs at once, for the fuzzer's precision test: every
// bug must be found, each exactly once. Single-threaded poll() loop over the reference handler
// (slave/handler), except where a bug says otherwise. The planted bugs (12):
//   1. crash: FC 0F with quantity 0 aborts the process
//   2. crash: FC 16 with AND mask 0000 and OR mask FFFF aborts the process
//   3. crash: FC 2B/0E read device id code 04 with an object id >= 80 aborts the process
//   4. whole-server hang: FC 14 asking for file number 0 sleeps 3 s in the server loop
//   5. silent deviation: frames with protocol id != 0 are answered
//   6. silent deviation: FC 03 with a quantity above 125 gets exception 02 instead of 03
//   7. never answers FC 07
//   8. stateful: FC 17 reads before it writes (the specification writes first)
//   9. framing: once a frame's header has arrived the server blocks reading the rest of it
//      (up to 2 s), stalling every other client
//  10. resource: only the first 100 concurrent connections are served; later ones are
//      accepted and never answered
//  11. half-close: requests that arrive together with the client's FIN are dropped unanswered
//  12. crash: FC 06 writing 7E57 to register 0A0B aborts the process. One value at one address
//      (1 in 2^32 for a guess, neither a boundary nor a map edge): the black-box mode does not
//      find it; coverage mode reads both constants from the server's comparisons
//      (tests/scripts/fuzz_coverage_multi_fault.sh)
// Usage as broken_server_common.hpp (--port, --respawn, --pid-file, --exit-after-s).
#include <fcntl.h>

#include <chrono>
#include <thread>

#include "broken_server_common.hpp"

namespace {

using mbstorm::codec::load_be16;
using mbstorm::codec::store_be16;

constexpr std::size_t kServedConnections = 100;

// Runs one request PDU through the reference handler; the response PDU (empty: no answer).
std::vector<std::uint8_t> handle_pdu(const std::vector<std::uint8_t>& pdu,
                                     mbstorm::slave::DataModel& model) {
    std::uint8_t out[mbstorm::slave::kMinOutput];
    const auto r =
        mbstorm::slave::handle_request(mbstorm::codec::Bytes(pdu.data(), pdu.size()), model,
                                       mbstorm::codec::MutableBytes(out, sizeof out));
    if (r.outcome == mbstorm::slave::Outcome::NoResponse) return {};
    return {out, out + r.size};
}

// Bug 8: FC 17 answered with the registers as they were before its own write.
bool read_before_write(const std::uint8_t* adu, std::size_t size, std::vector<std::uint8_t>& reply,
                       mbstorm::slave::DataModel& model) {
    if (size < 6 + 1 + 10 || adu[7] != 0x17) return false;
    const std::uint8_t* p = adu + 7;
    const std::uint16_t rq = load_be16(p + 3), wq = load_be16(p + 7);
    if (rq < 1 || rq > 125 || wq < 1 || wq > 121 || p[9] != 2 * wq || size != 7u + 10 + 2 * wq)
        return false;  // invalid: the reference handler answers it
    std::vector<std::uint8_t> read = {0x03, p[1], p[2], p[3], p[4]};
    const auto before = handle_pdu(read, model);
    if (before.empty() || (before[0] & 0x80)) return false;
    std::vector<std::uint8_t> write = {0x10, p[5], p[6], p[7], p[8], p[9]};
    write.insert(write.end(), p + 10, p + 10 + 2 * wq);
    const auto w = handle_pdu(write, model);
    if (w.empty() || (w[0] & 0x80)) return false;
    reply.assign(adu, adu + 7);
    reply[2] = reply[3] = 0;
    store_be16(reply.data() + 4, static_cast<std::uint16_t>(1 + before.size()));
    reply.insert(reply.end(), before.begin(), before.end());
    reply[7] = 0x17;
    return true;
}

broken::Action planted(const std::uint8_t* adu, std::size_t size, std::vector<std::uint8_t>& reply,
                       mbstorm::slave::DataModel& model) {
    if (size < 8) return broken::Action::Default;
    const std::uint8_t fc = adu[7];
    const std::uint8_t* p = adu + 7;
    const std::size_t n = size - 7;
    if (fc == 0x0F && n >= 5 && p[3] == 0 && p[4] == 0) std::abort();  // 1
    if (fc == 0x06 && n == 5 && load_be16(p + 1) == 0x0A0B && load_be16(p + 3) == 0x7E57)
        std::abort();  // 12
    if (fc == 0x16 && n >= 7 && load_be16(p + 3) == 0 && load_be16(p + 5) == 0xFFFF)
        std::abort();                                                                        // 2
    if (fc == 0x2B && n >= 4 && p[1] == 0x0E && p[2] == 0x04 && p[3] >= 0x80) std::abort();  // 3
    if (fc == 0x14 && n >= 5 && p[2] == 6 && load_be16(p + 3) == 0)
        std::this_thread::sleep_for(std::chrono::seconds(3));  // 4: the whole loop waits
    if (fc == 0x03 && n >= 5 && load_be16(p + 3) > 125 && load_be16(p + 3) != 0) {
        broken::exception_reply(adu, 0x02, reply);  // 6
        return broken::Action::Reply;
    }
    if (fc == 0x07) return broken::Action::Silent;                                 // 7
    if (read_before_write(adu, size, reply, model)) return broken::Action::Reply;  // 8
    return broken::Action::Default;
}

struct Conn {
    broken::Client client;
    bool served = false;  // among the first kServedConnections (bug 10)
};

// Bug 9: the rest of a started frame is read with the whole server waiting for it.
void complete_frame_blocking(broken::Client& c) {
    if (c.in.size() < 7) return;
    const std::size_t want = 6u + load_be16(c.in.data() + 4);
    if (want > 260 || c.in.size() >= want) return;
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(2);
    std::uint8_t buf[512];
    while (c.in.size() < want && std::chrono::steady_clock::now() < until) {
        pollfd p{c.fd, POLLIN, 0};
        if (::poll(&p, 1, 20) <= 0) continue;
        const ssize_t got = ::recv(c.fd, buf, std::min(sizeof buf, want - c.in.size()), 0);
        if (got <= 0) return;
        c.in.insert(c.in.end(), buf, buf + got);
    }
}

int serve_multi(int listen_fd, const broken::Faults& f) {
    mbstorm::slave::DataModel model;
    std::vector<Conn> conns;
    std::vector<pollfd> fds;
    std::uint8_t buf[8192];
    for (;;) {
        fds.assign(1, pollfd{listen_fd, POLLIN, 0});
        for (const Conn& c : conns)
            fds.push_back(
                pollfd{c.client.fd, static_cast<short>(c.served ? POLLIN : POLLRDHUP), 0});
        if (::poll(fds.data(), fds.size(), 1000) < 0 && errno != EINTR) return 1;
        if (fds[0].revents & POLLIN) {
            for (;;) {
                const int fd = ::accept4(listen_fd, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
                if (fd < 0) break;
                int one = 1;
                ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
                std::size_t served = 0;
                for (const Conn& c : conns) served += c.served;
                conns.push_back(Conn{broken::Client{fd, {}, false}, served < kServedConnections});
            }
        }
        std::vector<Conn> keep;
        for (std::size_t i = 0; i < conns.size(); ++i) {
            Conn& c = conns[i];
            const short rev = i + 1 < fds.size() ? fds[i + 1].revents : 0;
            bool open = true;
            if (!c.served) {
                open = !(rev & (POLLRDHUP | POLLHUP | POLLERR));
            } else if (rev & (POLLIN | POLLHUP | POLLERR)) {
                // Everything that is there, then decide: data that came with the FIN is
                // dropped with the connection (bug 11).
                bool eof = false, got = false;
                for (;;) {
                    const ssize_t n = ::recv(c.client.fd, buf, sizeof buf, 0);
                    if (n > 0) {
                        c.client.in.insert(c.client.in.end(), buf, buf + n);
                        got = true;
                        continue;
                    }
                    eof = n == 0 || (errno != EAGAIN && errno != EINTR);
                    break;
                }
                if (eof) {
                    open = false;
                } else if (got) {
                    complete_frame_blocking(c.client);
                    open = broken::consume(c.client, f, model);
                }
            }
            if (open)
                keep.push_back(std::move(c));
            else
                ::close(c.client.fd);
        }
        conns = std::move(keep);
    }
}

}  // namespace

int main(int argc, char** argv) {
    broken::Faults f;
    f.on_frame = planted;
    f.answer_any_protocol = true;  // 5
    return broken::main_with(argc, argv, f, serve_multi);
}
