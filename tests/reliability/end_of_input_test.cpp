// What the slave owes a client whose input ends: every complete request received before a
// half-close or before a fatally malformed frame is answered before the connection closes;
// and a frame that drips in too slowly closes its connection.
#include <gtest/gtest.h>
#include <sys/socket.h>

#include <memory>
#include <vector>

#include "../server/client_test_support.hpp"
#include "server/server.hpp"
#include "server/stats.hpp"

using namespace mbstorm;
using test::Client;
using test::read_holding;

namespace {

std::unique_ptr<server::Server> start(server::ServerConfig config) {
    auto s = std::make_unique<server::Server>(std::move(config));
    const Error error = s->start();
    EXPECT_TRUE(error.ok()) << error.text();
    return s;
}

std::vector<std::uint8_t> requests(int count, std::uint16_t first_tid, std::uint16_t quantity = 1) {
    std::vector<std::uint8_t> out;
    for (int i = 0; i < count; ++i) {
        auto r = read_holding(static_cast<std::uint16_t>(first_tid + i), 1, 0, quantity);
        out.insert(out.end(), r.begin(), r.end());
    }
    return out;
}

// Reads until the server closes; returns how many whole FC03 answers arrived, in order from
// first_tid (counting stops at the first one out of place).
int answers_until_close(Client& c, std::uint16_t first_tid, std::uint16_t quantity = 1) {
    const std::size_t size = test::read_holding_response_size(quantity);
    std::vector<std::uint8_t> got;
    std::uint8_t buf[4096];
    for (;;) {
        pollfd p{c.fd(), POLLIN, 0};
        if (::poll(&p, 1, test::kTimeoutMs) != 1) return -1;  // never closed
        const ssize_t r = ::recv(c.fd(), buf, sizeof buf, 0);
        if (r <= 0) break;
        got.insert(got.end(), buf, buf + r);
    }
    int n = 0;
    for (std::size_t at = 0; at + size <= got.size(); at += size, ++n) {
        const std::uint16_t tid = static_cast<std::uint16_t>(first_tid + n);
        if (got[at] != (tid >> 8) || got[at + 1] != (tid & 0xFF) || got[at + 7] != 3) break;
    }
    return n;
}

}  // namespace

// Before: the read of the end of the stream closed the connection at once, so the answer
// queued in the same batch was thrown away (answered 6 of 50 tries).
TEST(EndOfInput, HalfCloseAfterRequestsStillGetsEveryAnswer) {
    auto srv = start(test::test_config());
    for (int count : {1, 5, 50}) {
        for (int attempt = 0; attempt < 30; ++attempt) {
            Client c(*srv);
            ASSERT_TRUE(c.ok());
            ASSERT_TRUE(c.send_all(requests(count, 1)));
            ASSERT_EQ(::shutdown(c.fd(), SHUT_WR), 0);
            ASSERT_EQ(answers_until_close(c, 1), count) << count << " requests, try " << attempt;
        }
    }
}

// Before: the fatal header closed the connection with the earlier answers still queued.
TEST(EndOfInput, RequestsBeforeAFatalFrameInTheSameSendAreAnswered) {
    auto srv = start(test::test_config());
    for (int attempt = 0; attempt < 30; ++attempt) {
        Client c(*srv);
        ASSERT_TRUE(c.ok());
        auto bytes = requests(5, 10);
        const std::vector<std::uint8_t> length_zero = {0, 99, 0, 0, 0, 0, 1, 3};
        bytes.insert(bytes.end(), length_zero.begin(), length_zero.end());
        bytes.resize(bytes.size() + 40, 0xAA);  // garbage after it is ignored
        ASSERT_TRUE(c.send_all(bytes));
        ASSERT_EQ(answers_until_close(c, 10), 5) << "try " << attempt;
    }
    EXPECT_TRUE(test::eventually([&] { return srv->stats().bad_framing_closes == 30; }));
    EXPECT_TRUE(test::eventually([&] { return srv->stats().connections_current == 0; }));
}

TEST(EndOfInput, HalfCloseWithAPartialFrameAnswersTheCompleteOnesAndCloses) {
    auto srv = start(test::test_config());
    Client c(*srv);
    auto bytes = requests(3, 1);
    bytes.resize(bytes.size() + 5);  // the start of a fourth that never completes
    ASSERT_TRUE(c.send_all(bytes));
    ASSERT_EQ(::shutdown(c.fd(), SHUT_WR), 0);
    EXPECT_EQ(answers_until_close(c, 1), 3);
}

TEST(EndOfInput, HalfCloseWhilePausedForBackpressureAnswersEverything) {
    auto config = test::test_config();
    config.max_pending_output = 512;
    config.socket_send_buffer = 4096;
    auto srv = start(config);
    Client c(*srv, "127.0.0.1", 4096);
    // Far more answers (500 KB) than the socket buffers and the output cap hold: the server
    // pauses reading, stashes what arrived, and must still answer all of it after the
    // half-close.
    const int count = 2000;
    ASSERT_TRUE(c.send_all(requests(count, 1, 125)));
    ASSERT_EQ(::shutdown(c.fd(), SHUT_WR), 0);
    EXPECT_TRUE(test::eventually([&] { return srv->stats().backpressure_pauses > 0; }));
    EXPECT_EQ(answers_until_close(c, 1, 125), count);
}

// Before: every byte reset the idle timer, so a header announcing 254 bytes followed by one
// byte at a time held the connection forever.
TEST(FrameTimeout, ASlowDripIsClosedAndCounted) {
    auto config = test::test_config();
    config.idle_timeout_ms = 400;
    config.frame_timeout_ms = 300;
    auto srv = start(config);
    Client drip(*srv);
    Client steady(*srv);
    const std::vector<std::uint8_t> header = {0, 1, 0, 0, 0, 254, 1, 16};
    ASSERT_TRUE(drip.send_all(header));
    bool closed = false;
    // One byte every 100 ms: well inside the idle timeout, never a whole frame. Bounded: 30
    // bytes (3 s, ten times the frame timeout).
    for (int i = 0; i < 30 && !closed; ++i) {
        std::uint8_t b = 0;
        ::usleep(100'000);
        closed = !drip.send_all(&b, 1) || drip.closed_by_peer(1);
        ASSERT_TRUE(steady.send_all(read_holding(static_cast<std::uint16_t>(i), 1, 0, 1)));
        ASSERT_EQ(steady.recv_n(test::read_holding_response_size(1)).size(),
                  test::read_holding_response_size(1));
    }
    EXPECT_TRUE(closed || drip.closed_by_peer());
    EXPECT_TRUE(test::eventually([&] { return srv->stats().frame_timeouts == 1; }));
    EXPECT_EQ(srv->stats().idle_closes, 0u);
    EXPECT_EQ(srv->stats().connections_current, 1u);  // the steady client stays
}

TEST(FrameTimeout, FramesSplitAcrossSendsWithinTheBoundAreServed) {
    auto config = test::test_config();
    config.frame_timeout_ms = 2000;
    auto srv = start(config);
    Client c(*srv);
    // Each frame arrives in two halves 20 ms apart, forever starting new partial frames: the
    // bound is per frame, not per connection.
    for (int i = 0; i < 20; ++i) {
        auto r = read_holding(static_cast<std::uint16_t>(i), 1, 0, 1);
        ASSERT_TRUE(c.send_all(r.data(), 5));
        ::usleep(20'000);
        ASSERT_TRUE(c.send_all(r.data() + 5, r.size() - 5));
        ASSERT_EQ(c.recv_n(test::read_holding_response_size(1)).size(),
                  test::read_holding_response_size(1));
    }
    EXPECT_EQ(srv->stats().frame_timeouts, 0u);
}

TEST(FrameTimeout, ZeroMeansNoBound) {
    auto config = test::test_config();
    config.frame_timeout_ms = 0;
    auto srv = start(config);
    Client c(*srv);
    auto r = read_holding(1, 1, 0, 1);
    ASSERT_TRUE(c.send_all(r.data(), 3));
    EXPECT_TRUE(c.silent_for(300));
    ASSERT_TRUE(c.send_all(r.data() + 3, r.size() - 3));
    EXPECT_EQ(c.recv_n(test::read_holding_response_size(1)).size(),
              test::read_holding_response_size(1));
}
