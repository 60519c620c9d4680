// Connections past the descriptor limit: when RLIMIT_NOFILE cannot cover the connection limit,
// the server says so at start and lowers its connection limit below the descriptor limit, so
// that new clients evict the oldest idle ones (or are refused) instead of hanging unaccepted.
#include <fcntl.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>

#include <memory>
#include <vector>

#include "../server/client_test_support.hpp"
#include "net/features.hpp"
#include "server/server.hpp"

using namespace mbstorm;
using test::Client;
using test::read_holding;

namespace {

// Lowers the soft RLIMIT_NOFILE to `headroom` above the lowest free descriptor; restores it
// on destruction, even after a failed assertion.
class LoweredFdLimit {
  public:
    LoweredFdLimit() { getrlimit(RLIMIT_NOFILE, &saved_); }
    ~LoweredFdLimit() { setrlimit(RLIMIT_NOFILE, &saved_); }
    LoweredFdLimit(const LoweredFdLimit&) = delete;
    LoweredFdLimit& operator=(const LoweredFdLimit&) = delete;
    bool lower(int headroom) {
        const int lowest_free = fcntl(0, F_DUPFD_CLOEXEC, 0);
        if (lowest_free < 0) return false;
        ::close(lowest_free);
        rlimit lim = saved_;
        lim.rlim_cur = static_cast<rlim_t>(lowest_free + headroom);
        return lim.rlim_cur <= saved_.rlim_cur && setrlimit(RLIMIT_NOFILE, &lim) == 0;
    }

  private:
    rlimit saved_{};
};

bool answered(Client& c, std::uint16_t tid) {
    if (!c.send_all(read_holding(tid, 1, 0, 1))) return false;
    auto r = c.recv_n(test::read_holding_response_size(1), 3000);
    return r.size() == test::read_holding_response_size(1) && r[1] == (tid & 0xFF);
}

void run_past_the_descriptor_limit(server::FullPolicy policy) {
    (void)net::features();  // probed now: its rings and sockets take descriptors
    // The clients live in this process too: their sockets exist before the limit is lowered.
    constexpr int kClients = 60;
    std::vector<std::unique_ptr<Client>> clients;
    for (int i = 0; i < kClients; ++i)
        clients.push_back(std::make_unique<Client>(Client::DeferConnect{}));
    LoweredFdLimit limit;
    if (!limit.lower(48)) GTEST_SKIP() << "cannot lower RLIMIT_NOFILE";
    auto config = test::test_config();
    config.raise_nofile_limit = false;  // as if the hard limit were reached (root could raise it)
    config.full_policy = policy;        // the default limit, 16384, is far above the 48
    config.use_direct_descriptors = false;  // descriptors, as on a kernel without direct ones
    server::Server srv(config);
    const Error error = srv.start();
    ASSERT_TRUE(error.ok()) << error.text();
    EXPECT_THAT(srv.warning(), testing::HasSubstr("connection limit lowered from 16384 to"));
    const std::uint32_t effective = srv.config().max_connections;
    ASSERT_LT(effective, 48u);
    ASSERT_GT(effective, 0u);

    int served = 0, refused = 0;
    for (int i = 0; i < kClients; ++i) {
        Client& c = *clients[static_cast<std::size_t>(i)];
        ASSERT_TRUE(c.connect(srv)) << i;
        if (answered(c, static_cast<std::uint16_t>(i))) {
            ++served;
        } else {
            // Refused (closed at once), never left hanging: a hang fails here after 3 s.
            ASSERT_EQ(policy, server::FullPolicy::Refuse) << "client " << i << " not answered";
            ASSERT_TRUE(c.closed_by_peer(3000)) << "client " << i << " hangs";
            ++refused;
        }
    }
    const auto s = srv.stats();
    EXPECT_EQ(s.accept_fd_exhausted, 0u);  // the connection limit came first
    if (policy == server::FullPolicy::EvictOldestIdle) {
        EXPECT_EQ(served, kClients);
        EXPECT_EQ(s.evictions, kClients - effective);
    } else {
        EXPECT_EQ(served, static_cast<int>(effective));
        EXPECT_EQ(refused, kClients - static_cast<int>(effective));
    }
    srv.stop();
    clients.clear();
}

}  // namespace

// Before: nothing was said at start, nothing was evicted, and clients past ~the descriptor
// limit hung unaccepted.
TEST(FdLimit, BelowTheConnectionLimitEvictsInsteadOfHanging) {
    run_past_the_descriptor_limit(server::FullPolicy::EvictOldestIdle);
}

TEST(FdLimit, BelowTheConnectionLimitRefusesInsteadOfHanging) {
    run_past_the_descriptor_limit(server::FullPolicy::Refuse);
}

TEST(FdLimit, AmpleLimitChangesNothing) {
    auto config = test::test_config();
    config.max_connections = 4;
    server::Server srv(config);
    const Error error = srv.start();
    ASSERT_TRUE(error.ok()) << error.text();
    EXPECT_EQ(srv.config().max_connections, 4u);
    EXPECT_EQ(srv.warning(), "");
}
