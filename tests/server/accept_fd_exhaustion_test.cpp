// When the process runs out of file descriptors, accept fails with EMFILE at once and keeps
// failing until one is freed. The server must pause accepting (not spin a core re-arming it),
// keep serving its open connections, and accept again once descriptors are free.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cerrno>
#include <ctime>
#include <memory>
#include <vector>

#include "client_test_support.hpp"
#include "net/features.hpp"
#include "server/server.hpp"

using namespace mbstorm;
using test::Client;
using test::read_holding;

namespace {

double process_cpu_seconds() {
    timespec ts{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) / 1e9;
}

double monotonic_seconds() {
    timespec ts{};
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) / 1e9;
}

// Lowers the soft RLIMIT_NOFILE and fills every free descriptor below it with placeholders;
// the destructor closes them and restores the limit even when an assertion failed.
class FdExhaustion {
  public:
    FdExhaustion() { getrlimit(RLIMIT_NOFILE, &saved_); }
    ~FdExhaustion() { release(); }
    FdExhaustion(const FdExhaustion&) = delete;
    FdExhaustion& operator=(const FdExhaustion&) = delete;

    // New descriptors must be numbered below lowest-free + headroom (room for the server's
    // listener, eventfd and ring).
    bool lower(int template_fd, int headroom) {
        const int lowest_free = fcntl(template_fd, F_DUPFD_CLOEXEC, 0);
        if (lowest_free < 0) return false;
        ::close(lowest_free);
        rlimit lim = saved_;
        lim.rlim_cur = static_cast<rlim_t>(lowest_free + headroom);
        if (lim.rlim_cur > saved_.rlim_cur) return false;
        return setrlimit(RLIMIT_NOFILE, &lim) == 0;
    }
    // Takes every descriptor still free under the limit. True when the process is out of them.
    bool fill(int template_fd) {
        for (int i = 0; i < 4096; ++i) {
            const int fd = fcntl(template_fd, F_DUPFD_CLOEXEC, 0);
            if (fd < 0) return errno == EMFILE;
            placeholders_.push_back(fd);
        }
        return false;
    }
    void release() {
        for (int fd : placeholders_) ::close(fd);
        placeholders_.clear();
        setrlimit(RLIMIT_NOFILE, &saved_);
    }

  private:
    rlimit saved_{};
    std::vector<int> placeholders_;
};

bool answers(Client& c, std::uint16_t tid) {
    if (!c.send_all(read_holding(tid, 1, 0, 10))) return false;
    auto r = c.recv_n(test::read_holding_response_size(10));
    return r.size() == test::read_holding_response_size(10) && r[0] == (tid >> 8) &&
           r[1] == (tid & 0xFF) && r[7] == 3;
}

}  // namespace

TEST(AcceptFdExhaustion, PausesAcceptingWithoutSpinningAndRecovers) {
    (void)net::features();  // probed now: its rings and sockets take descriptors
    // Every client socket exists before the process runs out of descriptors.
    Client served(Client::DeferConnect{});
    std::vector<std::unique_ptr<Client>> waiting;
    for (int i = 0; i < 3; ++i) waiting.push_back(std::make_unique<Client>(Client::DeferConnect{}));
    ASSERT_TRUE(served.ok());
    for (auto& c : waiting) ASSERT_TRUE(c->ok());

    FdExhaustion exhaustion;
    // Lowered before the server starts: an accept takes the limit in force when it was armed.
    if (!exhaustion.lower(served.fd(), 16)) GTEST_SKIP() << "cannot lower RLIMIT_NOFILE";
    auto config = test::test_config();
    config.max_connections = 0;             // else start() raises the open-files limit again
    config.use_direct_descriptors = false;  // sockets as descriptors: they run out here
    server::Server srv(config);
    const Error error = srv.start();
    ASSERT_TRUE(error.ok()) << error.text();
    ASSERT_TRUE(served.connect(srv));
    ASSERT_TRUE(answers(served, 1));

    ASSERT_TRUE(exhaustion.fill(served.fd()));
    // The handshakes complete in the listen backlog; the server cannot take them.
    for (auto& c : waiting) ASSERT_TRUE(c->connect(srv));
    ASSERT_TRUE(test::eventually([&] { return srv.stats().accept_fd_exhausted > 0; }));

    // Re-arming the failing accept in a loop would burn about one CPU-second per second.
    const double cpu_before = process_cpu_seconds();
    const double wall_before = monotonic_seconds();
    ::usleep(300 * 1000);
    const double cpu_used = process_cpu_seconds() - cpu_before;
    const double wall = monotonic_seconds() - wall_before;
    EXPECT_LT(cpu_used, wall / 3) << "cpu " << cpu_used << " s in " << wall << " s";

    // Open connections are still served while accepting is paused.
    EXPECT_TRUE(answers(served, 2));
    EXPECT_EQ(srv.stats().connections_current, 1u);
    EXPECT_GT(srv.stats().accept_fd_exhausted, 0u);

    // With descriptors free again, the waiting connections and new ones are accepted.
    exhaustion.release();
    for (std::size_t i = 0; i < waiting.size(); ++i)
        EXPECT_TRUE(answers(*waiting[i], static_cast<std::uint16_t>(10 + i))) << i;
    Client fresh(srv);
    ASSERT_TRUE(fresh.ok());
    EXPECT_TRUE(answers(fresh, 20));
    EXPECT_TRUE(test::eventually([&] { return srv.stats().connections_current == 5u; }));
}
