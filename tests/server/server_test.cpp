#include <gtest/gtest.h>
#include <poll.h>

#include <chrono>
#include <memory>
#include <vector>

#include "client_test_support.hpp"
#include "codec/bytes.hpp"
#include "net/socket.hpp"
#include "server/server.hpp"
#include "server/stats.hpp"
#include "slave/data_model.hpp"

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

std::vector<std::uint8_t> burst(int count, std::uint16_t first_tid, std::uint8_t unit = 1) {
    std::vector<std::uint8_t> out;
    for (int i = 0; i < count; ++i) {
        auto r = read_holding(static_cast<std::uint16_t>(first_tid + i), unit, 0, 10);
        out.insert(out.end(), r.begin(), r.end());
    }
    return out;
}

// Checks `count` FC03 x10 responses in order with transaction ids from first_tid.
void expect_responses(Client& c, int count, std::uint16_t first_tid, std::uint8_t unit = 1) {
    const std::size_t size = test::read_holding_response_size(10);
    auto bytes = c.recv_n(size * count);
    ASSERT_EQ(bytes.size(), size * count);
    for (int i = 0; i < count; ++i) {
        const std::uint8_t* r = bytes.data() + i * size;
        const std::uint16_t tid = static_cast<std::uint16_t>(first_tid + i);
        ASSERT_EQ(r[0], tid >> 8) << i;
        ASSERT_EQ(r[1], tid & 0xFF) << i;
        ASSERT_EQ(r[2], 0);
        ASSERT_EQ(r[3], 0);
        ASSERT_EQ(r[5], 23);  // unit + fc + count + 20
        ASSERT_EQ(r[6], unit);
        ASSERT_EQ(r[7], 3);
        ASSERT_EQ(r[8], 20);
    }
}

}  // namespace

TEST(Server, AnswersOneRequest) {
    auto srv = start(test::test_config());
    srv->model().holding_registers().set(0, 0x1234);
    Client c(*srv);
    ASSERT_TRUE(c.ok());
    ASSERT_TRUE(c.send_all(read_holding(7, 9, 0, 10)));
    auto r = c.recv_n(29);
    ASSERT_EQ(r.size(), 29u);
    EXPECT_EQ(r[1], 7);
    EXPECT_EQ(r[6], 9);
    EXPECT_EQ(r[9], 0x12);
    EXPECT_EQ(r[10], 0x34);
    EXPECT_EQ(srv->stats().transactions, 1u);
}

TEST(Server, PipelinedBurstOfThousandInOneSend) {
    auto srv = start(test::test_config());
    Client c(*srv);
    ASSERT_TRUE(c.send_all(burst(1000, 100)));
    expect_responses(c, 1000, 100);
    // The client can see the last bytes before the server has counted its send completion.
    EXPECT_TRUE(test::eventually([&] { return srv->stats().bytes_out == 29000u; }));
    auto s = srv->stats();
    EXPECT_EQ(s.transactions, 1000u);
    EXPECT_EQ(s.bytes_in, 12000u);
    // Counted per frame loop rather than per frame (issue #18): the same totals.
    EXPECT_EQ(s.requests, 1000u);
    EXPECT_EQ(s.requests_by_function[3], 1000u);
    EXPECT_EQ(s.pending_output, 0u);
}

TEST(Server, DiagnosticsSeeTheReadsPipelinedBeforeThem) {
    // The reads answered inline are counted once per frame loop (issue #18): an FC0C in the
    // same recv still sees every read before it, and the next recv sees the whole batch.
    auto srv = start(test::test_config());
    Client c(*srv);
    auto bytes = burst(40, 1);
    const std::vector<std::uint8_t> event_log = {0x01, 0x00, 0x00, 0x00, 0x00, 0x02, 0x01, 0x0C};
    bytes.insert(bytes.end(), event_log.begin(), event_log.end());
    bytes.insert(bytes.end(), event_log.begin(), event_log.end());
    ASSERT_TRUE(c.send_all(bytes));
    expect_responses(c, 40, 1);
    for (int round = 0; round < 2; ++round) {
        // 32 pairs (64 bytes) of log, newest first (send 0x40, receive 0x80): reads, and in
        // the second answer the first FC0C's own pair too.
        const auto r = c.recv_n(7 + 8 + 64);
        ASSERT_EQ(r.size(), 7u + 8u + 64u) << round;
        const std::uint8_t* pdu = r.data() + 7;
        EXPECT_EQ(pdu[0], 0x0C);
        EXPECT_EQ(pdu[1], 6 + 64);
        EXPECT_EQ(codec::load_be16(pdu + 4), 40) << "event count";  // fetches do not count
        EXPECT_EQ(codec::load_be16(pdu + 6), 41 + round) << "message count, with itself";
        for (int i = 0; i < 32; ++i) {
            EXPECT_EQ(pdu[8 + 2 * i], 0x40) << round << " " << i;
            EXPECT_EQ(pdu[9 + 2 * i], 0x80) << round << " " << i;
        }
    }
    Client fresh(*srv);
    ASSERT_TRUE(fresh.send_all(event_log));
    const auto r = fresh.recv_n(7 + 8 + 64);
    ASSERT_EQ(r.size(), 7u + 8u + 64u);
    EXPECT_EQ(codec::load_be16(r.data() + 7 + 6), 43);
}

TEST(Server, PipelinedReadsAtEveryWordOffsetAreAnsweredExactly) {
    // The server copies registers a 64-bit word at a time, overwriting a few bytes either
    // side of the answer (issue #18): pipelined answers at every start lane and length must
    // still be exact, headers and neighbours included.
    auto srv = start(test::test_config());
    for (std::uint16_t a = 0; a < 64; ++a)
        srv->model().holding_registers().set(a, static_cast<std::uint16_t>(0x1100 + a * 0x0101));
    Client c(*srv);
    std::vector<std::uint8_t> requests;
    std::vector<std::pair<std::uint16_t, std::uint16_t>> reads;  // address, quantity
    for (std::uint16_t address = 0; address < 8; ++address)
        for (std::uint16_t quantity = 1; quantity <= 13; ++quantity) {
            const auto tid = static_cast<std::uint16_t>(reads.size());
            auto r = read_holding(tid, 5, address, quantity);
            requests.insert(requests.end(), r.begin(), r.end());
            reads.emplace_back(address, quantity);
        }
    ASSERT_TRUE(c.send_all(requests));
    for (std::size_t i = 0; i < reads.size(); ++i) {
        const auto [address, quantity] = reads[i];
        const auto r = c.recv_n(test::read_holding_response_size(quantity));
        ASSERT_EQ(r.size(), test::read_holding_response_size(quantity)) << i;
        EXPECT_EQ(codec::load_be16(r.data()), i);
        EXPECT_EQ(codec::load_be16(r.data() + 2), 0);
        EXPECT_EQ(codec::load_be16(r.data() + 4), 3 + 2 * quantity);
        EXPECT_EQ(r[6], 5);
        EXPECT_EQ(r[7], 3);
        EXPECT_EQ(r[8], 2 * quantity);
        for (std::uint16_t k = 0; k < quantity; ++k)
            ASSERT_EQ(codec::load_be16(r.data() + 9 + 2 * k), 0x1100 + (address + k) * 0x0101)
                << address << " " << quantity << " " << k;
    }
}

TEST(Server, ShortcutReadsAreCountedUnderTheirFunction) {
    // FC03/04 answered by the frame loop's shortcut are counted per frame loop (issue #18).
    auto srv = start(test::test_config());
    Client c(*srv);
    std::vector<std::uint8_t> requests;
    for (std::uint16_t i = 0; i < 5; ++i) {
        auto r = read_holding(i, 1, i, 2);
        if (i >= 3) r[7] = 0x04;  // read input registers
        requests.insert(requests.end(), r.begin(), r.end());
    }
    const std::vector<std::uint8_t> write = {0, 5, 0, 0, 0, 6, 1, 0x06, 0, 9, 0x12, 0x34};
    requests.insert(requests.end(), write.begin(), write.end());
    ASSERT_TRUE(c.send_all(requests));
    ASSERT_EQ(c.recv_n(5 * test::read_holding_response_size(2) + 12).size(),
              5 * test::read_holding_response_size(2) + 12);
    const auto s = srv->stats();
    EXPECT_EQ(s.requests, 6u);
    EXPECT_EQ(s.requests_by_function[3], 3u);
    EXPECT_EQ(s.requests_by_function[4], 2u);
    EXPECT_EQ(s.requests_by_function[6], 1u);
    EXPECT_EQ(srv->model().holding_registers().get(9), 0x1234);
}

TEST(Server, ByteByByteFragments) {
    auto srv = start(test::test_config());
    Client c(*srv);
    Client other(*srv);
    auto bytes = burst(5, 1);
    for (std::size_t i = 0; i < bytes.size(); ++i) {
        ASSERT_TRUE(c.send_all(&bytes[i], 1));
        if (i == 3) {
            // A connection holding half a frame never delays another.
            ASSERT_TRUE(other.send_all(read_holding(77, 1, 0, 10)));
            expect_responses(other, 1, 77);
        }
    }
    expect_responses(c, 5, 1);
}

TEST(Server, BadProtocolIdIsDiscardedAndConnectionStays) {
    auto srv = start(test::test_config());
    Client c(*srv);
    auto bad = read_holding(1, 1, 0, 10);
    bad[3] = 1;  // protocol id 1
    ASSERT_TRUE(c.send_all(bad));
    ASSERT_TRUE(c.send_all(read_holding(2, 1, 0, 10)));
    expect_responses(c, 1, 2);
    EXPECT_EQ(srv->stats().discarded_frames, 1u);
}

class BadLength : public ::testing::TestWithParam<int> {};

TEST_P(BadLength, ClosesOnlyThatConnection) {
    auto srv = start(test::test_config());
    Client bad(*srv);
    Client good(*srv);
    ASSERT_TRUE(good.send_all(read_holding(1, 1, 0, 10)));
    expect_responses(good, 1, 1);
    const int length = GetParam();
    std::vector<std::uint8_t> frame = {
        0, 1, 0, 0, static_cast<std::uint8_t>(length >> 8), static_cast<std::uint8_t>(length),
        1, 3};
    frame.resize(300, 0);
    ASSERT_TRUE(bad.send_all(frame));
    EXPECT_TRUE(bad.closed_by_peer());
    ASSERT_TRUE(good.send_all(read_holding(2, 1, 0, 10)));
    expect_responses(good, 1, 2);
    EXPECT_TRUE(test::eventually([&] { return srv->stats().bad_framing_closes == 1; }));
    EXPECT_EQ(srv->stats().connections_current, 1u);
}

INSTANTIATE_TEST_SUITE_P(Lengths, BadLength, ::testing::Values(0, 1, 255, 0xFFFF));

TEST(Server, ThousandConcurrentConnections) {
    std::string msg;
    if (net::raise_nofile_limit(2200, &msg) < 2200) GTEST_SKIP() << msg;
    auto config = test::test_config();
    config.threads = 2;
    auto srv = start(config);
    std::vector<Client> clients;
    clients.reserve(1000);
    for (int i = 0; i < 1000; ++i) {
        clients.emplace_back(*srv);
        ASSERT_TRUE(clients.back().ok()) << i;
    }
    for (int i = 0; i < 1000; ++i)
        ASSERT_TRUE(clients[i].send_all(read_holding(static_cast<std::uint16_t>(i), 1, 0, 10)));
    for (int i = 0; i < 1000; ++i) expect_responses(clients[i], 1, static_cast<std::uint16_t>(i));
    EXPECT_TRUE(test::eventually([&] { return srv->stats().connections_current == 1000; }));
    EXPECT_EQ(srv->stats().connections_total, 1000u);
}

TEST(Server, BackpressureBoundsPendingOutput) {
    auto config = test::test_config();
    config.socket_send_buffer = 8192;  // so that the kernel does not absorb megabytes
    auto srv = start(config);
    Client c(*srv, "127.0.0.1", 4096);
    net::set_nonblocking(c.fd());
    // Up to 100k requests without reading: the server must stop reading, not queue forever.
    auto chunk = burst(1000, 0);
    std::size_t sent_requests = 0;
    for (int round = 0; round < 100; ++round) {
        std::size_t off = 0;
        int stuck_polls = 0;
        while (off < chunk.size()) {
            ssize_t r = ::send(c.fd(), chunk.data() + off, chunk.size() - off, MSG_NOSIGNAL);
            if (r > 0) {
                off += static_cast<std::size_t>(r);
                continue;
            }
            pollfd p{c.fd(), POLLOUT, 0};
            if (::poll(&p, 1, 300) == 0 && ++stuck_polls >= 3) break;
        }
        sent_requests += off / 12;
        if (off < chunk.size()) {
            // Finish the partial frame so the count of answers is exact.
            std::size_t tail = (12 - off % 12) % 12;
            net::set_nonblocking(c.fd(), false);
            if (tail) {
                ASSERT_TRUE(c.send_all(chunk.data() + off, tail));
                ++sent_requests;
            }
            break;
        }
    }
    // The kernel buffers part of it; the server then fills its queue and stops reading.
    EXPECT_TRUE(test::eventually([&] { return srv->stats().backpressure_pauses > 0; }))
        << sent_requests << " requests sent";
    ::usleep(200'000);
    auto s = srv->stats();
    EXPECT_LT(s.transactions, sent_requests);  // still not all read: the client is not reading
    // Cap plus at most one receive buffer's worth of answers (4096/12 x 29 bytes).
    EXPECT_LE(s.pending_output_peak, config.max_pending_output + 16 * 1024);
    EXPECT_LE(s.pending_output, config.max_pending_output + 16 * 1024);
    net::set_nonblocking(c.fd(), false);
    // Reading drains everything: every request is answered.
    std::vector<std::uint8_t> buf(29 * 1000);
    std::size_t remaining = sent_requests * 29;
    while (remaining > 0) {
        std::size_t n = std::min(remaining, buf.size());
        ASSERT_TRUE(c.recv_exact(buf.data(), n)) << remaining;
        remaining -= n;
    }
    EXPECT_TRUE(test::eventually([&] { return srv->stats().transactions == sent_requests; }));
}

TEST(Server, IdleTimeoutCloses) {
    auto config = test::test_config();
    config.idle_timeout_ms = 200;
    auto srv = start(config);
    Client c(*srv);
    ASSERT_TRUE(c.send_all(read_holding(1, 1, 0, 10)));
    expect_responses(c, 1, 1);
    EXPECT_TRUE(c.closed_by_peer());
    EXPECT_EQ(srv->stats().idle_closes, 1u);
}

TEST(Server, MaxConnectionsEvictsOldestIdle) {
    auto config = test::test_config();
    config.max_connections = 2;
    auto srv = start(config);
    Client a(*srv), b(*srv);
    ASSERT_TRUE(test::eventually([&] { return srv->stats().connections_current == 2; }));
    ASSERT_TRUE(a.send_all(read_holding(1, 1, 0, 10)));
    expect_responses(a, 1, 1);  // a is now the most recently active; b is the oldest idle
    Client c(*srv);
    EXPECT_TRUE(b.closed_by_peer());
    ASSERT_TRUE(c.send_all(read_holding(3, 1, 0, 10)));
    expect_responses(c, 1, 3);
    ASSERT_TRUE(a.send_all(read_holding(4, 1, 0, 10)));
    expect_responses(a, 1, 4);
    EXPECT_EQ(srv->stats().evictions, 1u);
}

TEST(Server, MaxConnectionsEvictsTheServerWideOldestAcrossThreads) {
    // Four threads: the kernel spreads connections over their listening sockets, so the
    // oldest idle connection usually belongs to another thread than the one accepting the
    // newcomer. Whichever it is, the oldest must go and the others stay, every round.
    auto config = test::test_config();
    config.threads = 4;
    config.max_connections = 4;
    auto srv = start(config);
    std::uint16_t tid = 1;
    std::vector<std::unique_ptr<Client>> open;
    for (int i = 0; i < 4; ++i) {
        open.push_back(std::make_unique<Client>(*srv));
        ASSERT_TRUE(open.back()->send_all(read_holding(tid, 1, 0, 10)));
        expect_responses(*open.back(), 1, tid++);
    }
    for (int round = 0; round < 8; ++round) {
        // Activity on all but the front makes the front the server-wide oldest idle one.
        for (std::size_t i = 1; i < open.size(); ++i) {
            ASSERT_TRUE(open[i]->send_all(read_holding(tid, 1, 0, 10)));
            expect_responses(*open[i], 1, tid++);
        }
        auto newcomer = std::make_unique<Client>(*srv);
        EXPECT_TRUE(open.front()->closed_by_peer()) << "round " << round;
        for (std::size_t i = 1; i < open.size(); ++i) {
            ASSERT_TRUE(open[i]->send_all(read_holding(tid, 1, 0, 10))) << "round " << round;
            expect_responses(*open[i], 1, tid++);
        }
        ASSERT_TRUE(newcomer->send_all(read_holding(tid, 1, 0, 10)));
        expect_responses(*newcomer, 1, tid++);
        open.erase(open.begin());
        open.push_back(std::move(newcomer));
    }
    // An eviction is counted when it is decided and the connection counted gone when its close
    // completes, later (seen 5 open once, under the epoll backend beside other tests): both
    // are waited for.
    EXPECT_TRUE(test::eventually([&] {
        const auto s = srv->stats();
        return s.evictions == 8u && s.connections_current == 4u;
    }));
    EXPECT_EQ(srv->stats().evictions, 8u);
    EXPECT_EQ(srv->stats().connections_current, 4u);
}

TEST(Server, MaxConnectionsRefuses) {
    auto config = test::test_config();
    config.max_connections = 2;
    config.full_policy = server::FullPolicy::Refuse;
    auto srv = start(config);
    Client a(*srv), b(*srv);
    ASSERT_TRUE(test::eventually([&] { return srv->stats().connections_current == 2; }));
    Client c(*srv);
    EXPECT_TRUE(c.closed_by_peer());
    ASSERT_TRUE(a.send_all(read_holding(1, 1, 0, 10)));
    expect_responses(a, 1, 1);
    EXPECT_EQ(srv->stats().refusals, 1u);
}

TEST(Server, OutstandingCapAnswersBusy) {
    auto config = test::test_config();
    config.max_outstanding = 4;
    auto srv = start(config);
    Client c(*srv);
    ASSERT_TRUE(c.send_all(burst(10, 0)));  // one send: one batch on loopback
    expect_responses(c, 4, 0);
    for (int i = 4; i < 10; ++i) {
        auto r = c.recv_n(9);
        ASSERT_EQ(r.size(), 9u);
        EXPECT_EQ(r[1], i);
        EXPECT_EQ(r[7], 0x83);
        EXPECT_EQ(r[8], 0x06);
    }
    EXPECT_EQ(srv->stats().busy_rejects, 6u);
    // Once answered, the next batch is served again.
    ASSERT_TRUE(c.send_all(burst(2, 50)));
    expect_responses(c, 2, 50);
}

TEST(Server, UnitFilterNoAnswer) {
    auto config = test::test_config();
    config.only_unit = 5;
    auto srv = start(config);
    Client c(*srv);
    ASSERT_TRUE(c.send_all(read_holding(1, 6, 0, 10)));
    ASSERT_TRUE(c.send_all(read_holding(2, 5, 0, 10)));
    expect_responses(c, 1, 2, 5);
    EXPECT_TRUE(c.silent_for(200));
    EXPECT_EQ(srv->stats().foreign_unit, 1u);
}

TEST(Server, UnitFilterGatewayException) {
    auto config = test::test_config();
    config.only_unit = 5;
    config.foreign_unit = server::ForeignUnitPolicy::GatewayException;
    auto srv = start(config);
    Client c(*srv);
    ASSERT_TRUE(c.send_all(read_holding(1, 6, 0, 10)));
    auto r = c.recv_n(9);
    ASSERT_EQ(r.size(), 9u);
    EXPECT_EQ(r[6], 6);
    EXPECT_EQ(r[7], 0x83);
    EXPECT_EQ(r[8], 0x0B);
}

TEST(Server, FaultExceptions) {
    auto config = test::test_config();
    config.faults.exception_rate = 1.0;
    config.faults.exception_code = codec::ExceptionCode::ServerDeviceBusy;
    auto srv = start(config);
    Client c(*srv);
    ASSERT_TRUE(c.send_all(burst(3, 0)));
    for (int i = 0; i < 3; ++i) {
        auto r = c.recv_n(9);
        ASSERT_EQ(r.size(), 9u);
        EXPECT_EQ(r[1], i);
        EXPECT_EQ(r[7], 0x83);
        EXPECT_EQ(r[8], 0x06);
    }
    EXPECT_EQ(srv->stats().exceptions[6], 3u);
}

TEST(Server, FaultDropClosesConnection) {
    auto config = test::test_config();
    config.faults.drop_rate = 1.0;
    auto srv = start(config);
    Client c(*srv);
    ASSERT_TRUE(c.send_all(read_holding(1, 1, 0, 10)));
    EXPECT_TRUE(c.closed_by_peer());
    EXPECT_EQ(srv->stats().fault_drops, 1u);
}

TEST(Server, FaultNoAnswer) {
    auto config = test::test_config();
    config.faults.no_answer_rate = 1.0;
    auto srv = start(config);
    Client c(*srv);
    ASSERT_TRUE(c.send_all(burst(3, 0)));
    EXPECT_TRUE(c.silent_for(300));
    EXPECT_EQ(srv->stats().fault_no_answer, 3u);
}

TEST(Server, FaultDelayHoldsAndKeepsOrder) {
    auto config = test::test_config();
    config.faults.delay.kind = slave::DelayConfig::Kind::Uniform;
    config.faults.delay.min_ns = 50'000'000;
    config.faults.delay.max_ns = 250'000'000;
    auto srv = start(config);
    Client c(*srv);
    const auto sent_at = std::chrono::steady_clock::now();
    ASSERT_TRUE(c.send_all(burst(20, 0)));
    expect_responses(c, 20, 0);
    // A lower bound only (the server holds every answer at least min_ns after reading it).
    EXPECT_GE(std::chrono::steady_clock::now() - sent_at, std::chrono::milliseconds(50));
    EXPECT_EQ(srv->stats().fault_delayed, 20u);
}

TEST(Server, FaultStallHoldsEverything) {
    auto config = test::test_config();
    config.faults.stall.period_ns = 100'000'000;
    config.faults.stall.duration_ns = 99'000'000;  // stalled 99% of the time
    auto srv = start(config);
    Client c(*srv);
    // The first stall starts one period after the server started.
    for (int i = 0; i < 5; ++i) {
        ::usleep(30'000);
        ASSERT_TRUE(c.send_all(burst(5, 0)));
        expect_responses(c, 5, 0);
    }
    EXPECT_GT(srv->stats().fault_delayed, 0u);
}

TEST(Server, GracefulStopClosesClients) {
    auto srv = start(test::test_config());
    Client c(*srv);
    ASSERT_TRUE(c.send_all(read_holding(1, 1, 0, 10)));
    expect_responses(c, 1, 1);
    srv->stop();
    EXPECT_TRUE(c.closed_by_peer());
    auto s = srv->stats();
    EXPECT_EQ(s.transactions, 1u);
    EXPECT_EQ(s.connections_current, 0u);
    auto text = server::format_summary(s, 1.0);
    EXPECT_NE(text.find("1 transactions"), std::string::npos);
}

TEST(Server, FallbackWithoutBufferRing) {
    auto config = test::test_config();
    config.use_buf_ring = false;
    config.use_multishot_accept = false;
    auto srv = start(config);
    Client c(*srv);
    ASSERT_TRUE(c.send_all(burst(1000, 0)));
    expect_responses(c, 1000, 0);
}

TEST(Server, SingleShotRecvWithBufferRing) {
    auto config = test::test_config();
    config.use_multishot_recv = false;
    auto srv = start(config);
    Client c(*srv);
    ASSERT_TRUE(c.send_all(burst(1000, 0)));
    expect_responses(c, 1000, 0);
}

TEST(Server, TinyBufferRingSurvivesExhaustion) {
    auto config = test::test_config();
    config.buf_ring_count = 2;
    config.buf_size = 64;
    auto srv = start(config);
    std::vector<Client> clients;
    for (int i = 0; i < 8; ++i) clients.emplace_back(*srv);
    for (auto& c : clients) ASSERT_TRUE(c.send_all(burst(200, 0)));
    for (auto& c : clients) expect_responses(c, 200, 0);
}

TEST(Server, Ipv6Loopback) {
    const Result<net::UniqueFd> probe = net::listen_socket(*net::parse_endpoint("[::1]:0"));
    if (!probe.ok()) GTEST_SKIP() << "no IPv6 loopback";
    auto config = test::test_config();
    config.listen = "[::1]:0";
    auto srv = start(config);
    EXPECT_EQ(srv->endpoint().front(), '[');
    Client c(*srv, "::1");
    ASSERT_TRUE(c.ok());
    ASSERT_TRUE(c.send_all(read_holding(1, 1, 0, 10)));
    expect_responses(c, 1, 1);
}

TEST(Server, MultipleThreadsShareThePort) {
    auto config = test::test_config();
    config.threads = 2;
    auto srv = start(config);
    EXPECT_EQ(srv->threads(), 2u);
    std::vector<Client> clients;
    for (int i = 0; i < 40; ++i) clients.emplace_back(*srv);
    for (auto& c : clients) ASSERT_TRUE(c.send_all(burst(10, 0)));
    for (auto& c : clients) expect_responses(c, 10, 0);
    EXPECT_EQ(srv->stats().transactions, 400u);
}

TEST(Server, ReportsSmallIdleConnectionFootprint) {
    // Per idle connection: fixed state only (the splitter's 260-byte frame buffer dominates).
    EXPECT_LE(server::Server::bytes_per_connection(), 512u);
}

TEST(Server, SurvivesRandomGarbage) {
    auto srv = start(test::test_config());
    std::uint64_t state = 0x9E3779B97F4A7C15ull;
    auto next = [&] {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        return state;
    };
    for (int round = 0; round < 50; ++round) {
        Client c(*srv);
        ASSERT_TRUE(c.ok());
        std::vector<std::uint8_t> junk(1 + next() % 2000);
        for (auto& b : junk) b = static_cast<std::uint8_t>(next());
        if (round % 2 == 0) {  // a valid-looking header with a random PDU
            junk.resize(std::max<std::size_t>(junk.size(), 8));
            junk[2] = junk[3] = 0;
            junk[4] = 0;
            junk[5] = static_cast<std::uint8_t>(std::min<std::size_t>(junk.size() - 6, 254));
        }
        c.send_all(junk);
    }
    Client good(*srv);
    ASSERT_TRUE(good.send_all(read_holding(1, 1, 0, 10)));
    expect_responses(good, 1, 1);
}
