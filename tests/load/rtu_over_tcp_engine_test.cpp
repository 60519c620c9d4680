// The load engine speaking RTU over TCP: against the in-process reference slave in RTU mode,
// against a peer whose answers fail their CRC (a class of its own, then a fresh connection) or
// come after the timeout (a fresh connection too),
// and the plan check that keeps RTU at one outstanding request per connection.
#include <gtest/gtest.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <thread>
#include <utility>
#include <vector>

#include "codec/rtu.hpp"
#include "load/engine.hpp"
#include "net/socket.hpp"
#include "server/server.hpp"

namespace mbstorm::load {
namespace {

using namespace std::chrono_literals;
using stats::Outcome;

Plan rtu_plan(std::uint16_t port) {
    Plan plan;
    plan.host = "127.0.0.1";
    plan.port = port;
    plan.framing = codec::Framing::Rtu;
    Operation op;
    op.name = "read";
    op.function = 0x03;
    op.first_address = 0;
    op.last_address = 99;
    op.quantity = 4;
    plan.operations = {op};
    plan.threads = 1;
    plan.depth = 1;
    plan.duration = 10s;  // ended by the transaction count long before
    return plan;
}

TEST(RtuOverTcpEngine, AgainstTheRtuSlaveEveryAnswerIsMatchedAndChecked) {
    server::ServerConfig config;
    config.listen = "127.0.0.1:0";
    config.threads = 1;
    config.framing = codec::Framing::Rtu;
    server::Server srv(config);
    const Error error = srv.start();
    ASSERT_TRUE(error.ok()) << error.text();
    Plan plan = rtu_plan(srv.port());
    plan.connections = 4;
    plan.transactions = 2000;
    const LoadResult r = run_load(plan);
    ASSERT_TRUE(r.ok()) << r.error;
    EXPECT_EQ(r.run.counters.transactions_sent, 2000u);
    EXPECT_EQ(r.run.counters.ok(), 2000u);
    EXPECT_EQ(r.crc_errors, 0u);
    EXPECT_EQ(r.framing_errors, 0u);
    EXPECT_EQ(srv.stats().transactions, 2000u);
}

TEST(RtuOverTcpEngine, MbapEngineAgainstAnRtuSlaveGetsNoAnswers) {
    // The wrong framing on one side must show as errors, never as successes.
    server::ServerConfig config;
    config.listen = "127.0.0.1:0";
    config.threads = 1;
    config.framing = codec::Framing::Rtu;
    server::Server srv(config);
    const Error error = srv.start();
    ASSERT_TRUE(error.ok()) << error.text();
    Plan plan = rtu_plan(srv.port());
    plan.framing = codec::Framing::Mbap;
    plan.transactions = 20;
    plan.duration = 2s;
    plan.transaction_timeout = 200ms;
    const LoadResult r = run_load(plan);
    EXPECT_EQ(r.run.counters.ok(), 0u);
}

// A hand-written RTU-over-TCP slave: `answer(request number, request, fd)` decides what each
// request gets (requests are numbered across all connections, from 0).
class ScriptedRtuPeer {
  public:
    using Answer = std::function<void(int n, const std::uint8_t* request, int fd)>;
    explicit ScriptedRtuPeer(Answer answer) : answer_(std::move(answer)) {
        const net::Endpoint ep = *net::parse_endpoint("127.0.0.1:0");
        net::ListenOptions lo;
        lo.nonblocking = true;
        lo.reuse_port = false;
        listener_ = net::listen_socket(ep, lo).value();
        sockaddr_storage a{};
        socklen_t len = sizeof a;
        ::getsockname(listener_.get(), reinterpret_cast<sockaddr*>(&a), &len);
        port_ = ntohs(reinterpret_cast<sockaddr_in*>(&a)->sin_port);
        thread_ = std::thread([this] { serve(); });
    }
    ~ScriptedRtuPeer() {
        stop_ = true;
        thread_.join();
    }
    std::uint16_t port() const { return port_; }
    std::atomic<int> accepted{0};

  private:
    void serve() {
        std::vector<net::UniqueFd> conns;
        int requests = 0;
        const auto end = std::chrono::steady_clock::now() + 30s;
        while (!stop_ && std::chrono::steady_clock::now() < end) {
            std::vector<pollfd> ps{{listener_.get(), POLLIN, 0}};
            for (auto& c : conns) ps.push_back({c.get(), POLLIN, 0});
            if (::poll(ps.data(), ps.size(), 20) <= 0) continue;
            if (ps[0].revents & POLLIN) {
                const int fd = ::accept(listener_.get(), nullptr, nullptr);
                if (fd >= 0) {
                    conns.emplace_back(fd);
                    ++accepted;
                }
            }
            for (std::size_t i = 1; i < ps.size(); ++i) {
                if (!(ps[i].revents & (POLLIN | POLLHUP))) continue;
                std::uint8_t buf[256];
                const ssize_t n = ::recv(ps[i].fd, buf, sizeof buf, 0);
                if (n >= 8) answer_(requests++, buf, ps[i].fd);
            }
        }
    }
    Answer answer_;
    net::UniqueFd listener_;
    std::uint16_t port_ = 0;
    std::atomic<bool> stop_{false};
    std::thread thread_;
};

// Unit, 03, eight bytes of registers and the CRC, XORed with `crc_flip` (1: a wrong CRC).
void send_read_answer(int fd, std::uint8_t unit, std::uint16_t crc_flip) {
    std::uint8_t answer[13] = {unit, 3, 8};
    const std::uint16_t crc = codec::crc16(codec::Bytes(answer, 11)) ^ crc_flip;
    answer[11] = static_cast<std::uint8_t>(crc & 0xFF);
    answer[12] = static_cast<std::uint8_t>(crc >> 8);
    (void)::send(fd, answer, sizeof answer, MSG_NOSIGNAL);
}

TEST(RtuOverTcpEngine, BadCrcIsItsOwnErrorClassAndTheConnectionIsRenewed) {
    ScriptedRtuPeer peer(
        [](int, const std::uint8_t* request, int fd) { send_read_answer(fd, request[0], 1); });
    Plan plan = rtu_plan(peer.port());
    plan.connections = 1;
    plan.transactions = 5;
    plan.reconnect_backoff_min = 1ms;
    plan.reconnect_backoff_max = 10ms;
    const LoadResult r = run_load(plan);
    ASSERT_TRUE(r.ok()) << r.error;
    EXPECT_EQ(r.run.counters.ok(), 0u);
    EXPECT_EQ(r.run.counters.count(Outcome::CrcError), 5u);
    EXPECT_EQ(r.crc_errors, 5u);
    EXPECT_EQ(r.framing_errors, 0u);
    EXPECT_GE(peer.accepted.load(), 5);
}

TEST(RtuOverTcpEngine, ATimedOutRequestRenewsTheConnectionSoItsLateAnswerPassesForNoOther) {
    // RTU answers carry no transaction id: on the same connection, the first request's late
    // answer would be taken for the second request's, and the second's for nothing.
    // The first answer is held back past the timeout and sent just before the second one, on
    // the first request's connection.
    ScriptedRtuPeer peer([held_fd = -1](int n, const std::uint8_t* request, int fd) mutable {
        if (n == 0) {
            held_fd = fd;
            return;
        }
        if (held_fd >= 0) send_read_answer(std::exchange(held_fd, -1), request[0], 0);
        send_read_answer(fd, request[0], 0);
    });
    Plan plan = rtu_plan(peer.port());
    plan.connections = 1;
    plan.transactions = 5;
    plan.transaction_timeout = 100ms;
    plan.reconnect_backoff_min = 1ms;
    plan.reconnect_backoff_max = 10ms;
    const LoadResult r = run_load(plan);
    ASSERT_TRUE(r.ok()) << r.error;
    EXPECT_EQ(r.run.counters.count(Outcome::Timeout), 1u);
    EXPECT_EQ(r.run.counters.ok(), 4u);
    EXPECT_EQ(r.late_responses, 0u);
    EXPECT_EQ(r.run.counters.stray_responses(), 0u);
    EXPECT_EQ(peer.accepted.load(), 2);
}

TEST(RtuOverTcpEngine, PlanRefusesPipelining) {
    Plan plan = rtu_plan(502);
    plan.depth = 2;
    const Error problem = validate_plan(plan);
    ASSERT_EQ(problem.code(), ErrorCode::InvalidInput);
    EXPECT_NE(problem.message().find("RTU over TCP"), std::string::npos) << problem;
    plan.depth = 1;
    EXPECT_TRUE(validate_plan(plan).ok());
}

}  // namespace
}  // namespace mbstorm::load
