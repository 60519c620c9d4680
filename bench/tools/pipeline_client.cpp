// Single-threaded epoll load client: N connections, each keeping D FC03 x10 requests
// outstanding. Whatever arrives in one read is answered with as many new requests in one
// write(). Runs for a bounded time and prints transactions/s and p50/p99 latency.
//
//   pipeline_client --port P [--host 127.0.0.1] [--connections N] [--depth D]
//                   [--seconds S] [--warmup S]
// Last line: "RESULT tps=<n> p50_us=<x> p99_us=<y> connections=<N> depth=<D>"
#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <signal.h>
#include <sys/epoll.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace {

std::int64_t now_ns() {
    timespec ts{};
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1'000'000'000LL + ts.tv_nsec;
}

// Log-linear latency histogram: 64 sub-buckets per power of two of nanoseconds.
class Histogram {
  public:
    void record(std::int64_t ns) {
        if (ns < 1) ns = 1;
        auto v = static_cast<std::uint64_t>(ns);
        int msb = 63 - __builtin_clzll(v);
        int sub = msb < 6 ? static_cast<int>(v) : static_cast<int>((v >> (msb - 6)) & 63);
        std::size_t idx =
            msb < 6 ? static_cast<std::size_t>(v) : static_cast<std::size_t>(msb) * 64 + sub;
        if (idx >= counts_.size()) idx = counts_.size() - 1;
        ++counts_[idx];
        ++total_;
    }
    double percentile_us(double p) const {
        if (total_ == 0) return 0;
        auto want = static_cast<std::uint64_t>(p / 100.0 * static_cast<double>(total_));
        std::uint64_t seen = 0;
        for (std::size_t i = 0; i < counts_.size(); ++i) {
            seen += counts_[i];
            if (seen > want) return static_cast<double>(value_of(i)) / 1000.0;
        }
        return 0;
    }
    void clear() {
        counts_.assign(counts_.size(), 0);
        total_ = 0;
    }

  private:
    static std::uint64_t value_of(std::size_t idx) {
        if (idx < 64) return idx;
        std::size_t msb = idx / 64, sub = idx % 64;
        return (1ull << msb) | (static_cast<std::uint64_t>(sub) << (msb - 6));
    }
    std::vector<std::uint64_t> counts_ = std::vector<std::uint64_t>(64 * 64, 0);
    std::uint64_t total_ = 0;
};

struct Conn {
    int fd = -1;
    std::vector<std::int64_t> sent_at;  // FIFO of send times, capacity depth
    std::size_t head = 0, count = 0;
    std::uint16_t next_tid = 0;
    unsigned char partial[300];
    std::size_t partial_len = 0;
};

volatile sig_atomic_t g_stop = 0;

}  // namespace

int main(int argc, char** argv) {
    std::string host = "127.0.0.1";
    int port = 5020, connections = 1, depth = 1;
    double seconds = 3, warmup = 0.5;
    for (int i = 1; i + 1 < argc; i += 2) {
        std::string a = argv[i];
        const char* v = argv[i + 1];
        if (a == "--host")
            host = v;
        else if (a == "--port")
            port = std::atoi(v);
        else if (a == "--connections")
            connections = std::atoi(v);
        else if (a == "--depth")
            depth = std::atoi(v);
        else if (a == "--seconds")
            seconds = std::atof(v);
        else if (a == "--warmup")
            warmup = std::atof(v);
        else {
            std::fprintf(stderr, "unknown option %s\n", a.c_str());
            return 2;
        }
    }
    if (connections < 1 || depth < 1 || depth > 4096 || seconds <= 0 || seconds > 600) {
        std::fprintf(stderr, "bad arguments\n");
        return 2;
    }
    signal(SIGPIPE, SIG_IGN);
    signal(SIGINT, [](int) { g_stop = 1; });
    rlimit lim{};
    getrlimit(RLIMIT_NOFILE, &lim);
    lim.rlim_cur = lim.rlim_max;
    setrlimit(RLIMIT_NOFILE, &lim);

    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(static_cast<uint16_t>(port));
    if (inet_pton(AF_INET, host.c_str(), &addr.sin_addr) != 1) {
        std::fprintf(stderr, "bad host %s\n", host.c_str());
        return 2;
    }
    int ep = epoll_create1(0);
    std::vector<Conn> conns(static_cast<std::size_t>(connections));
    int one = 1;
    for (int i = 0; i < connections; ++i) {
        Conn& c = conns[static_cast<std::size_t>(i)];
        c.fd = socket(AF_INET, SOCK_STREAM, 0);
        if (connect(c.fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
            std::perror("pipeline_client: connect");
            return 1;
        }
        setsockopt(c.fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
        c.sent_at.assign(static_cast<std::size_t>(depth), 0);
        epoll_event ev{};
        ev.events = EPOLLIN;
        ev.data.u32 = static_cast<std::uint32_t>(i);
        epoll_ctl(ep, EPOLL_CTL_ADD, c.fd, &ev);
    }

    std::vector<unsigned char> out(static_cast<std::size_t>(depth) * 12);
    auto send_requests = [&](Conn& c, std::size_t n, std::int64_t t) -> bool {
        for (std::size_t k = 0; k < n; ++k) {
            unsigned char* r = out.data() + k * 12;
            const std::uint16_t tid = c.next_tid++;
            const unsigned char req[12] = {static_cast<unsigned char>(tid >> 8),
                                           static_cast<unsigned char>(tid),
                                           0,
                                           0,
                                           0,
                                           6,
                                           1,
                                           3,
                                           0,
                                           0,
                                           0,
                                           10};
            std::memcpy(r, req, 12);
            c.sent_at[(c.head + c.count) % c.sent_at.size()] = t;
            ++c.count;
        }
        std::size_t off = 0, total = n * 12;
        while (off < total) {  // requests are small: a blocking-style retry is fine here
            ssize_t w = send(c.fd, out.data() + off, total - off, MSG_NOSIGNAL | MSG_DONTWAIT);
            if (w > 0)
                off += static_cast<std::size_t>(w);
            else if (w < 0 && errno != EAGAIN && errno != EINTR)
                return false;
        }
        return true;
    };

    const std::int64_t start = now_ns();
    for (auto& c : conns)
        if (!send_requests(c, static_cast<std::size_t>(depth), start)) return 1;

    Histogram hist;
    std::uint64_t done = 0;
    const std::int64_t measure_from = start + static_cast<std::int64_t>(warmup * 1e9);
    const std::int64_t end = measure_from + static_cast<std::int64_t>(seconds * 1e9);
    bool measuring = warmup <= 0;
    std::vector<unsigned char> in(64 * 1024);
    epoll_event events[512];
    std::int64_t measured_start = measuring ? start : 0;
    while (!g_stop) {
        std::int64_t t = now_ns();
        if (t >= end) break;
        if (!measuring && t >= measure_from) {
            measuring = true;
            measured_start = t;
            hist.clear();
            done = 0;
        }
        int n = epoll_wait(ep, events, 512, 100);
        t = now_ns();
        for (int i = 0; i < n; ++i) {
            Conn& c = conns[events[i].data.u32];
            ssize_t r = recv(c.fd, in.data(), in.size(), MSG_DONTWAIT);
            if (r == 0 || (r < 0 && errno != EAGAIN)) {
                std::fprintf(stderr, "pipeline_client: connection closed by server\n");
                return 1;
            }
            if (r < 0) continue;
            // Split responses by their MBAP length; a frame may straddle reads.
            std::size_t answered = 0;
            const unsigned char* p = in.data();
            std::size_t left = static_cast<std::size_t>(r);
            while (left > 0) {
                if (c.partial_len < 6) {
                    std::size_t take = std::min(left, 6 - c.partial_len);
                    std::memcpy(c.partial + c.partial_len, p, take);
                    c.partial_len += take;
                    p += take;
                    left -= take;
                    if (c.partial_len < 6) break;
                }
                std::size_t frame = 6 + ((c.partial[4] << 8) | c.partial[5]);
                if (frame > sizeof c.partial) {
                    std::fprintf(stderr, "pipeline_client: bad frame length\n");
                    return 1;
                }
                std::size_t take = std::min(left, frame - c.partial_len);
                std::memcpy(c.partial + c.partial_len, p, take);
                c.partial_len += take;
                p += take;
                left -= take;
                if (c.partial_len == frame) {
                    c.partial_len = 0;
                    if (c.count == 0) {
                        std::fprintf(stderr, "pipeline_client: unsolicited response\n");
                        return 1;
                    }
                    hist.record(t - c.sent_at[c.head]);
                    c.head = (c.head + 1) % c.sent_at.size();
                    --c.count;
                    ++answered;
                }
            }
            done += answered;
            if (answered && !send_requests(c, answered, t)) return 1;
        }
    }
    const double elapsed = static_cast<double>(now_ns() - measured_start) / 1e9;
    const double tps = static_cast<double>(done) / elapsed;
    std::printf("transactions/s %.0f  p50 %.1f us  p99 %.1f us  (%d conns x depth %d, %.1fs)\n",
                tps, hist.percentile_us(50), hist.percentile_us(99), connections, depth, elapsed);
    std::printf("RESULT tps=%.0f p50_us=%.1f p99_us=%.1f connections=%d depth=%d\n", tps,
                hist.percentile_us(50), hist.percentile_us(99), connections, depth);
    for (auto& c : conns) close(c.fd);
    return 0;
}
