#include <gtest/gtest.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstring>

#include "net/buf_ring.hpp"
#include "net/clock.hpp"
#include "net/features.hpp"
#include "net/peer_queue.hpp"
#include "net/ring.hpp"
#include "net/socket.hpp"
#include "net/user_data.hpp"

using namespace mbstorm::net;
using mbstorm::Error;
using mbstorm::ErrorCode;
using mbstorm::Result;

namespace {

// The listener, or an invalid descriptor where the address cannot be listened on (no IPv6).
UniqueFd listen_or_invalid(const Endpoint& ep) {
    Result<UniqueFd> listener = listen_socket(ep);
    return listener.ok() ? std::move(listener).value() : UniqueFd();
}

}  // namespace

TEST(UserData, RoundTrips) {
    auto v = encode_user_data(3, 123456, 0xABCDEF);
    auto d = decode_user_data(v);
    EXPECT_EQ(d.op, 3);
    EXPECT_EQ(d.index, 123456u);
    EXPECT_EQ(d.generation, 0xABCDEFu);
    EXPECT_EQ(decode_user_data(encode_user_data(255, 0xFFFFFFFF, 0x1FFFFFF)).generation, 0xFFFFFFu);
    EXPECT_EQ(next_generation(kGenerationMask), 0u);
}

TEST(Endpoint, ParsesIpv4Ipv6AndDefaults) {
    Result<Endpoint> ep = parse_endpoint("127.0.0.1:5020");
    ASSERT_TRUE(ep.ok());
    EXPECT_EQ(ep->family(), AF_INET);
    EXPECT_EQ(ep->port(), 5020);
    EXPECT_EQ(ep->to_string(), "127.0.0.1:5020");
    ep = parse_endpoint("[::1]:5020");
    ASSERT_TRUE(ep.ok());
    EXPECT_EQ(ep->family(), AF_INET6);
    EXPECT_EQ(ep->to_string(), "[::1]:5020");
    ep = parse_endpoint("::1", 502);
    ASSERT_TRUE(ep.ok());
    EXPECT_EQ(ep->port(), 502);
    ep = parse_endpoint("10.0.0.1", 1502);
    ASSERT_TRUE(ep.ok());
    EXPECT_EQ(ep->port(), 1502);
    ep = parse_endpoint("localhost:7");
    ASSERT_TRUE(ep.ok()) << ep.error().text();
    EXPECT_EQ(ep->port(), 7);
}

TEST(Endpoint, OneTargetSyntaxSplitsWithoutResolving) {
    struct Case {
        const char* text;
        const char* host;
        std::uint16_t port;
    };
    for (const Case& c :
         {Case{"plc.example", "plc.example", 502}, Case{"10.0.0.1:1502", "10.0.0.1", 1502},
          Case{"[fe80::1]:5020", "fe80::1", 5020}, Case{"[::1]", "::1", 502},
          Case{"::1", "::1", 502}, Case{"2001:db8::7", "2001:db8::7", 502}}) {
        std::string host;
        std::uint16_t port = 502;
        ASSERT_TRUE(split_host_port(c.text, host, port).ok()) << c.text;
        EXPECT_EQ(host, c.host) << c.text;
        EXPECT_EQ(port, c.port) << c.text;
    }
    std::string host;
    std::uint16_t port = 502;
    EXPECT_EQ(split_host_port("host:", host, port).code(), ErrorCode::InvalidInput);
    const Error too_big = split_host_port("host:70000", host, port);
    EXPECT_EQ(too_big.code(), ErrorCode::InvalidInput);
    EXPECT_EQ(too_big.text(), "bad port in 'host:70000' (0..65535)");
    EXPECT_EQ(split_host_port("[::1]502", host, port).code(), ErrorCode::InvalidInput);
}

// Bad text is the user's input to fix; a name that does not resolve is the network's answer.
TEST(Endpoint, RejectsBadTextAsInvalidInputAndUnknownNamesAsNetwork) {
    for (const char* bad : {"127.0.0.1:99999", "[::1:5020", "[::1]x", "127.0.0.1:"}) {
        const Result<Endpoint> ep = parse_endpoint(bad);
        EXPECT_EQ(ep.error().code(), ErrorCode::InvalidInput) << bad;
        EXPECT_FALSE(ep.error().message().empty()) << bad;
    }
    const Result<Endpoint> unknown = parse_endpoint("no.such.host.invalid:1");
    EXPECT_EQ(unknown.error().code(), ErrorCode::Network);
    EXPECT_EQ(unknown.error().message().rfind("cannot resolve host 'no.such.host.invalid': ", 0),
              0u)
        << unknown.error().text();
}

// A port another socket holds (without SO_REUSEPORT on both) cannot be listened on: a Network
// error whose message is the system's reason alone, for the caller to say what it listened for.
TEST(Socket, ListeningOnATakenPortIsANetworkError) {
    Endpoint ep = *parse_endpoint("127.0.0.1:0");
    const ListenOptions exclusive{16, false, true};
    Result<UniqueFd> first = listen_socket(ep, exclusive);
    ASSERT_TRUE(first.ok()) << first.error().text();
    ep.set_port(local_port(first->get()));
    const Result<UniqueFd> second = listen_socket(ep, exclusive);
    ASSERT_FALSE(second.ok());
    EXPECT_EQ(second.error().code(), ErrorCode::Network);
    EXPECT_EQ(second.error().text(), "Address already in use");
}

TEST(Socket, ListenEphemeralAndConnect) {
    Endpoint ep = *parse_endpoint("127.0.0.1:0");
    UniqueFd l = listen_or_invalid(ep);
    ASSERT_TRUE(l.valid());
    std::uint16_t port = local_port(l.get());
    ASSERT_NE(port, 0);
    ep.set_port(port);
    // SO_REUSEPORT: a second listener on the same port works.
    UniqueFd l2 = listen_or_invalid(ep);
    EXPECT_TRUE(l2.valid());
    UniqueFd c(connect_nonblocking(ep));
    ASSERT_TRUE(c.valid());
    EXPECT_EQ(set_nodelay(c.get()), 0);
    UniqueFd b(connect_blocking(ep));
    EXPECT_TRUE(b.valid());
}

TEST(Socket, Ipv6Loopback) {
    Endpoint ep = *parse_endpoint("[::1]:0");
    UniqueFd l = listen_or_invalid(ep);
    if (!l.valid()) GTEST_SKIP() << "no IPv6 loopback";
    ep.set_port(local_port(l.get()));
    UniqueFd c(connect_blocking(ep));
    EXPECT_TRUE(c.valid());
}

// What the fuzzer waits on before the second piece of a split frame: the bytes the target's
// program has not read yet, read from the kernel's socket diagnostics, for IPv4 and IPv6.
TEST(PeerQueue, CountsTheBytesThePeersProgramHasNotRead) {
    for (const char* where : {"127.0.0.1:0", "[::1]:0"}) {
        Endpoint ep = *parse_endpoint(where);
        UniqueFd l = listen_or_invalid(ep);
        if (!l.valid()) continue;  // no IPv6 loopback here
        ep.set_port(local_port(l.get()));
        UniqueFd c(connect_blocking(ep));
        ASSERT_TRUE(c.valid());
        UniqueFd a(::accept(l.get(), nullptr, nullptr));
        ASSERT_TRUE(a.valid());
        EXPECT_EQ(bytes_unread_by_peer(c.get()), 0) << where;
        ASSERT_EQ(::send(c.get(), "hello", 5, 0), 5);
        EXPECT_EQ(bytes_unread_by_peer(c.get()), 5) << where;
        char buf[8];
        ASSERT_EQ(::recv(a.get(), buf, 3, 0), 3);
        EXPECT_EQ(bytes_unread_by_peer(c.get()), 2) << where;
        ASSERT_EQ(::recv(a.get(), buf, sizeof buf, 0), 2);
        EXPECT_EQ(bytes_unread_by_peer(c.get()), 0) << where;
        // Our side of the same connection: the counts go the other way.
        EXPECT_EQ(bytes_unread_by_peer(a.get()), 0) << where;
    }
}

TEST(PeerQueue, UnknownWithoutAConnectedPeer) {
    UniqueFd s(::socket(AF_INET, SOCK_STREAM, 0));
    EXPECT_EQ(bytes_unread_by_peer(s.get()), -1);
    EXPECT_EQ(bytes_unread_by_peer(-1), -1);
}

TEST(Socket, NofileLimitReportsWhenItCannotRaise) {
    std::string msg;
    auto got = raise_nofile_limit(64, &msg);
    EXPECT_GE(got, 64u);
    EXPECT_TRUE(msg.empty());
    auto big = raise_nofile_limit(1ull << 40, &msg);
    EXPECT_LT(big, 1ull << 40);
    EXPECT_NE(msg.find("ulimit -n"), std::string::npos);
}

TEST(Clock, IsMonotonic) {
    auto a = now_ns();
    auto b = now_ns();
    EXPECT_LE(a, b);
    EXPECT_GT(a, 0);
}

TEST(Features, ProbeDescribes) {
    const Features& f = features();
    std::string d = describe(f);
    EXPECT_NE(d.find("io_uring"), std::string::npos);
    if (f.ring) {
        EXPECT_NE(d.find("multishot_recv="), std::string::npos);
    }
}

TEST(Ring, InitFallsBackAndRunsANop) {
    Ring ring;
    ASSERT_EQ(ring.init(), 0);
    io_uring_sqe* sqe = ring.sqe();
    ASSERT_NE(sqe, nullptr);
    io_uring_prep_nop(sqe);
    io_uring_sqe_set_data64(sqe, 42);
    ASSERT_GE(ring.submit_and_wait(1, kNsPerSec), 0);
    std::uint64_t seen = 0;
    EXPECT_EQ(ring.drain([&](const io_uring_cqe& c) { seen = c.user_data; }), 1u);
    EXPECT_EQ(seen, 42u);
    RingOptions plain;
    plain.single_issuer = plain.defer_taskrun = plain.coop_taskrun = false;
    Ring r2;
    EXPECT_EQ(r2.init(plain), 0);
    Ring moved = std::move(r2);
    EXPECT_TRUE(moved.valid());
    EXPECT_FALSE(r2.valid());
}

TEST(Ring, TimeoutReturnsEtime) {
    Ring ring;
    ASSERT_EQ(ring.init(), 0);
    EXPECT_EQ(ring.submit_and_wait(1, 10 * kNsPerMs), -ETIME);
}

TEST(BufRing, RecvSelectsAndRecycles) {
    if (!features().buf_ring) GTEST_SKIP() << "no buffer rings";
    Ring ring;
    ASSERT_EQ(ring.init(), 0);
    BufRing br;
    EXPECT_EQ(br.init(ring.get(), 1, 3, 64), -EINVAL);  // not a power of two
    ASSERT_EQ(br.init(ring.get(), 1, 4, 64), 0);
    int sv[2];
    ASSERT_EQ(socketpair(AF_UNIX, SOCK_STREAM, 0, sv), 0);
    UniqueFd a(sv[0]), b(sv[1]);
    for (int round = 0; round < 10; ++round) {  // more rounds than buffers: recycling works
        char msg[16];
        std::snprintf(msg, sizeof msg, "r%d", round);
        ASSERT_GT(::write(b.get(), msg, std::strlen(msg)), 0);
        io_uring_sqe* sqe = ring.sqe();
        io_uring_prep_recv(sqe, a.get(), nullptr, 64, 0);
        sqe->flags |= IOSQE_BUFFER_SELECT;
        sqe->buf_group = 1;
        ASSERT_GE(ring.submit_and_wait(1, kNsPerSec), 0);
        ring.drain([&](const io_uring_cqe& c) {
            ASSERT_EQ(c.res, static_cast<int>(std::strlen(msg)));
            ASSERT_TRUE(BufRing::has_buffer(c.flags));
            auto id = BufRing::buffer_id(c.flags);
            EXPECT_EQ(std::memcmp(br.buffer(id), msg, std::strlen(msg)), 0);
            br.recycle(id);
        });
    }
    EXPECT_EQ(br.memory_bytes(), 4 * 64 + 4 * sizeof(io_uring_buf));
}
