// How the engine counts: stray responses (unknown or repeated transaction ids) are counted
// apart from transactions, and a transaction-count limit counts measured sends only.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <thread>
#include <vector>

#include "../support/loopback_listener.hpp"
#include "load/engine.hpp"
#include "server/server.hpp"

namespace mbstorm::load {
namespace {

using namespace std::chrono_literals;
using stats::Outcome;

// A faulty target on an ephemeral loopback port: answers every FC03 request twice (the second
// is a duplicate id) and after every fourth answer also sends one with an id nobody used.
class DoublingServer {
  public:
    DoublingServer() {
        listen_fd_ = test::listen_on_loopback(8, port_);
        EXPECT_GE(listen_fd_, 0);
        thread_ = std::thread([this] { serve(); });
    }
    ~DoublingServer() {
        stop_ = true;
        thread_.join();
        ::close(listen_fd_);
    }
    std::uint16_t port() const { return port_; }
    std::uint64_t unknown_sent() const { return unknown_sent_; }

  private:
    void serve() {
        pollfd p{listen_fd_, POLLIN, 0};
        while (!stop_ && ::poll(&p, 1, 50) <= 0) {
        }
        if (stop_) return;
        const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
        std::vector<std::uint8_t> in;
        std::uint8_t chunk[4096];
        std::uint64_t answered = 0;
        while (!stop_) {
            pollfd q{fd, POLLIN, 0};
            if (::poll(&q, 1, 50) <= 0) continue;
            const ssize_t n = ::recv(fd, chunk, sizeof chunk, 0);
            if (n <= 0) break;
            in.insert(in.end(), chunk, chunk + n);
            std::vector<std::uint8_t> out;
            std::size_t at = 0;
            while (in.size() - at >= 12) {  // FC03 requests only: always 12 bytes
                const std::uint8_t* r = in.data() + at;
                const std::uint16_t quantity = static_cast<std::uint16_t>(r[10] << 8 | r[11]);
                append_answer(out, r[0], r[1], r[6], quantity);
                append_answer(out, r[0], r[1], r[6], quantity);  // duplicate id
                if (++answered % 4 == 0) {
                    // An id 32768 away from one in use: never outstanding at depth 1.
                    append_answer(out, r[0] ^ 0x80, r[1], r[6], quantity);
                    ++unknown_sent_;
                }
                at += 12;
            }
            in.erase(in.begin(), in.begin() + static_cast<std::ptrdiff_t>(at));
            if (::send(fd, out.data(), out.size(), MSG_NOSIGNAL) < 0) break;
        }
        ::close(fd);
    }
    static void append_answer(std::vector<std::uint8_t>& out, std::uint8_t tid_hi,
                              std::uint8_t tid_lo, std::uint8_t unit, std::uint16_t quantity) {
        const std::uint16_t length = static_cast<std::uint16_t>(3 + 2 * quantity);
        const std::uint8_t header[] = {tid_hi,
                                       tid_lo,
                                       0,
                                       0,
                                       static_cast<std::uint8_t>(length >> 8),
                                       static_cast<std::uint8_t>(length),
                                       unit,
                                       0x03,
                                       static_cast<std::uint8_t>(2 * quantity)};
        out.insert(out.end(), header, header + sizeof header);
        out.insert(out.end(), 2u * quantity, 0);
    }

    int listen_fd_ = -1;
    std::uint16_t port_ = 0;
    std::atomic<bool> stop_{false};
    std::atomic<std::uint64_t> unknown_sent_{0};
    std::thread thread_;
};

Plan one_connection_plan(std::uint16_t port) {
    Plan plan;
    plan.host = "127.0.0.1";
    plan.port = port;
    Operation op;
    op.name = "read";
    op.function = 0x03;
    op.first_address = 0;
    op.last_address = 99;
    op.quantity = 2;
    plan.operations = {op};
    plan.threads = 1;
    plan.connections = 1;
    plan.depth = 1;
    return plan;
}

TEST(EngineAccounting, StrayResponsesAreCountedButAreNeitherTransactionsNorErrors) {
    DoublingServer server;
    Plan plan = one_connection_plan(server.port());
    plan.duration = 0s;
    plan.transactions = 2000;
    const LoadResult r = run_load(plan);
    ASSERT_TRUE(r.ok()) << r.error;
    const auto& c = r.run.counters;
    EXPECT_EQ(c.transactions_sent, 2000u);
    EXPECT_EQ(c.completed(), 2000u);
    EXPECT_EQ(c.ok(), 2000u);
    EXPECT_EQ(c.errors(), 0u);
    EXPECT_EQ(r.pending_at_end, 0u);
    // Every answer's twin is a duplicate, except those still on the wire when the run ended.
    EXPECT_GE(c.count(Outcome::DuplicateId), 1990u);
    EXPECT_LE(c.count(Outcome::DuplicateId), 2000u);
    EXPECT_GE(c.count(Outcome::UnknownId), 490u);
    EXPECT_LE(c.count(Outcome::UnknownId), server.unknown_sent());
    EXPECT_EQ(c.stray_responses(), c.count(Outcome::DuplicateId) + c.count(Outcome::UnknownId));
    // Throughput is per transaction: 2000 over the measured time, not the ~4500 responses.
    const double seconds = static_cast<double>(r.run.metadata.measured_duration_ns) / 1e9;
    EXPECT_NEAR(r.run.throughput() * seconds, 2000.0, 1.0);
}

TEST(EngineAccounting, TransactionLimitCountsOnlyMeasuredSends) {
    server::ServerConfig config;
    config.listen = "127.0.0.1:0";
    config.threads = 1;
    server::Server server(config);
    const Error error = server.start();
    ASSERT_TRUE(error.ok()) << error.text();
    Plan plan = one_connection_plan(server.port());
    plan.depth = 4;
    plan.duration = 0s;
    plan.warmup = 300ms;
    plan.transactions = 3000;
    const LoadResult r = run_load(plan);
    ASSERT_TRUE(r.ok()) << r.error;
    EXPECT_EQ(r.run.counters.transactions_sent, 3000u);
    EXPECT_EQ(r.run.counters.ok(), 3000u);
    EXPECT_EQ(r.run.latency.total_count(), 3000u);
    // The warm-up ran as well: the server answered more than the measured 3000.
    EXPECT_GT(server.stats().transactions, 3000u);
}

// Failed connects are counted by cause, named by their errno: a refusal as ECONNREFUSED, a
// connect nobody answers within the connect timeout as ETIMEDOUT.
TEST(EngineAccounting, FailedConnectsAreCountedByCause) {
    std::uint16_t port = 0;
    ::close(test::listen_on_loopback(1, port));  // nothing listens there now
    Plan plan = one_connection_plan(port);
    plan.duration = 1s;
    const LoadResult refused = run_load(plan);
    EXPECT_FALSE(refused.ok());
    EXPECT_EQ(refused.run.connections.failed, 1u);
    EXPECT_EQ(refused.run.connections.failed_by_cause,
              (std::map<std::string, std::uint64_t>{{"ECONNREFUSED", 1}}));

    // A listener whose accept queue is full drops further SYNs: the connect times out.
    const int full = test::listen_on_loopback(0, port);
    std::vector<int> fillers;
    for (int i = 0; i < 4; ++i) {
        const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK, 0);
        sockaddr_in to{};
        to.sin_family = AF_INET;
        to.sin_port = htons(port);
        to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        ::connect(fd, reinterpret_cast<sockaddr*>(&to), sizeof to);
        fillers.push_back(fd);
    }
    std::this_thread::sleep_for(50ms);
    plan.port = port;
    plan.connect_timeout = 200ms;
    const LoadResult timed_out = run_load(plan);
    EXPECT_FALSE(timed_out.ok());
    EXPECT_EQ(timed_out.run.connections.failed_by_cause,
              (std::map<std::string, std::uint64_t>{{"ETIMEDOUT", 1}}));
    for (const int fd : fillers) ::close(fd);
    ::close(full);
}

}  // namespace
}  // namespace mbstorm::load
