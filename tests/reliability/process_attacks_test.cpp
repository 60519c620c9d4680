// Attacks on the `mbstorm serve` and `mbstorm run` processes: clients that never read (the
// server's resident memory stays bounded), a slowloris crowd (closed by the frame timeout while
// a steady client is served), and SIGINT/SIGTERM on both sides (a clean stop with a summary,
// reports written, the right exit code).
#include <arpa/inet.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <thread>

#include "../server/client_test_support.hpp"
#include "child_process.hpp"
#include "hostile_target.hpp"

namespace mbstorm {
namespace {

using test::ChildProcess;
using testing::HasSubstr;

// Starts `mbstorm serve` on an ephemeral port; returns the port (0 on failure).
std::uint16_t start_serve(ChildProcess& serve) {
    const std::string marker = "listening on 127.0.0.1:";
    if (!serve.wait_for_output(marker) || !serve.wait_for_output(" (")) return 0;
    const auto at = serve.output().find(marker) + marker.size();
    return static_cast<std::uint16_t>(std::stoi(serve.output().substr(at)));
}

int connect_to(std::uint16_t port, bool nonblocking = false) {
    const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    addr.sin_port = htons(port);
    if (::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
        ::close(fd);
        return -1;
    }
    if (nonblocking) ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) | O_NONBLOCK);
    return fd;
}

bool answered(int fd, std::uint16_t tid) {
    const auto req = test::read_holding(tid, 1, 0, 1);
    if (::send(fd, req.data(), req.size(), MSG_NOSIGNAL) != static_cast<ssize_t>(req.size()))
        return false;
    std::uint8_t buf[11];
    std::size_t got = 0;
    while (got < sizeof buf) {
        pollfd p{fd, POLLIN, 0};
        if (::poll(&p, 1, 5000) != 1) return false;
        const ssize_t n = ::recv(fd, buf + got, sizeof buf - got, 0);
        if (n <= 0) return false;
        got += static_cast<std::size_t>(n);
    }
    return buf[1] == (tid & 0xFF) && buf[7] == 3;
}

// A client that never reads: 20 of them pipeline requests until their sockets block.
TEST(ProcessAttacks, ClientsThatNeverReadKeepTheServerResidentMemoryBounded) {
    ChildProcess serve({"serve", "--listen", "127.0.0.1:0", "--threads", "1"});
    const std::uint16_t port = start_serve(serve);
    ASSERT_NE(port, 0) << serve.output();
    const long before_kib = serve.rss_kib();
    std::vector<std::uint8_t> burst;
    for (int i = 0; i < 2000; ++i) {
        const auto r = test::read_holding(static_cast<std::uint16_t>(i), 1, 0, 125);
        burst.insert(burst.end(), r.begin(), r.end());
    }
    std::vector<int> fds;
    std::uint64_t sent = 0;
    for (int c = 0; c < 20; ++c) {
        const int fd = connect_to(port, true);
        ASSERT_GE(fd, 0);
        fds.push_back(fd);
        // Until the socket stays full for 3 polls of 100 ms, at most 50 MB per client.
        for (int stuck = 0, round = 0; stuck < 3 && round < 2000;) {
            const ssize_t n = ::send(fd, burst.data(), burst.size(), MSG_NOSIGNAL);
            if (n > 0) {
                sent += static_cast<std::uint64_t>(n);
                ++round;
                stuck = 0;
                continue;
            }
            pollfd p{fd, POLLOUT, 0};
            if (::poll(&p, 1, 100) == 0) ++stuck;
        }
    }
    const long after_kib = serve.rss_kib();
    // Each answer is 257 bytes for a 12-byte request: unbounded queues would hold gigabytes.
    EXPECT_LT(after_kib - before_kib, 48 * 1024) << "sent " << sent << " bytes";
    // Still serving others.
    const int other = connect_to(port);
    EXPECT_TRUE(answered(other, 7));
    ::close(other);
    for (int fd : fds) ::close(fd);
    serve.signal(SIGTERM);
    EXPECT_EQ(serve.wait(), 0) << serve.output();
    std::printf(
        "[ figures ] %llu request bytes unread by 20 clients; server RSS %ld KiB -> %ld KiB\n",
        static_cast<unsigned long long>(sent), before_kib, after_kib);
}

TEST(ProcessAttacks, SlowlorisCrowdIsClosedByTheFrameTimeoutWhileOthersAreServed) {
    ChildProcess serve({"serve", "--listen", "127.0.0.1:0", "--threads", "1", "--frame-timeout",
                        "500ms", "--stats"});
    const std::uint16_t port = start_serve(serve);
    ASSERT_NE(port, 0) << serve.output();
    constexpr int kCrowd = 1000;
    std::vector<int> crowd;
    const std::uint8_t half_header[] = {0, 1, 0, 0, 0};
    for (int i = 0; i < kCrowd; ++i) {
        const int fd = connect_to(port);
        ASSERT_GE(fd, 0) << i;
        ASSERT_EQ(::send(fd, half_header, sizeof half_header, MSG_NOSIGNAL), 5);
        crowd.push_back(fd);
    }
    const int steady = connect_to(port);
    for (int i = 0; i < 10; ++i) EXPECT_TRUE(answered(steady, static_cast<std::uint16_t>(i)));
    // Every member of the crowd is closed within the bound (generously: 10 s).
    int closed = 0;
    for (int fd : crowd) {
        pollfd p{fd, POLLIN, 0};
        std::uint8_t b;
        if (::poll(&p, 1, 10000) == 1 && ::recv(fd, &b, 1, 0) <= 0) ++closed;
        ::close(fd);
    }
    EXPECT_EQ(closed, kCrowd);
    EXPECT_TRUE(answered(steady, 99));
    ::close(steady);
    serve.signal(SIGINT);
    EXPECT_EQ(serve.wait(), 0) << serve.output();
    EXPECT_THAT(serve.output(), HasSubstr("1000 closed for a slow frame"));
}

// A client dripping a request head into --metrics-listen, a byte every 100 ms for 20 s, used
// to keep `serve -d 1s` alive until it left (the endpoint's one thread read it, and exit
// joined that thread). The server now exits at its duration, the client still dripping.
TEST(ProcessAttacks, ADrippingMetricsClientDoesNotKeepServeAlivePastItsDuration) {
    ChildProcess serve({"serve", "--listen", "127.0.0.1:0", "--threads", "1", "-d", "1s",
                        "--metrics-listen", "127.0.0.1:0"});
    const std::string marker = "metrics on http://127.0.0.1:";
    ASSERT_TRUE(serve.wait_for_output(marker)) << serve.output();
    ASSERT_TRUE(serve.wait_for_output("/metrics\n")) << serve.output();
    const auto at = serve.output().find(marker) + marker.size();
    const int fd = connect_to(static_cast<std::uint16_t>(std::stoi(serve.output().substr(at))));
    ASSERT_GE(fd, 0);
    std::atomic<bool> dripped_all{false};
    std::thread drip([&] {
        for (int i = 0; i < 200; ++i) {
            if (::send(fd, "G", 1, MSG_NOSIGNAL) != 1) return;
            std::this_thread::sleep_for(std::chrono::milliseconds(100));
        }
        dripped_all = true;
    });
    EXPECT_EQ(serve.wait(), 0) << serve.output();
    EXPECT_FALSE(dripped_all) << "serve outlived its duration until the client left";
    ::shutdown(fd, SHUT_RDWR);
    drip.join();
    ::close(fd);
}

TEST(ProcessAttacks, ServeStopsCleanlyOnSigtermAndSigint) {
    for (int sig : {SIGTERM, SIGINT}) {
        ChildProcess serve({"serve", "--listen", "127.0.0.1:0", "--threads", "1"});
        const std::uint16_t port = start_serve(serve);
        ASSERT_NE(port, 0) << serve.output();
        const int fd = connect_to(port);
        EXPECT_TRUE(answered(fd, 1));
        serve.signal(sig);
        EXPECT_EQ(serve.wait(), 0) << serve.output();
        EXPECT_THAT(serve.output(), HasSubstr("summary:"));
        EXPECT_THAT(serve.output(), HasSubstr("1 transactions"));
        ::close(fd);
    }
}

TEST(ProcessAttacks, RunStopsOnSigtermAndSigintWithEverythingReported) {
    test::HostileTarget target(test::HostileTarget::Mode::Honest);
    const auto dir = std::filesystem::temp_directory_path() /
                     ("mbstorm_reliability_signals_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    for (int sig : {SIGTERM, SIGINT}) {
        const auto json = (dir / ("r" + std::to_string(sig) + ".json")).string();
        ChildProcess run({"run", "--target", "127.0.0.1:" + std::to_string(target.port()), "-d",
                          "60s", "-c", "2", "--depth", "2", "--json", json});
        ASSERT_TRUE(run.wait_for_output("load test of")) << run.output();
        // Progress lines show that transactions are flowing.
        ASSERT_TRUE(run.wait_for_output("tx/s", 10000)) << run.output();
        run.signal(sig);
        // Interrupted is not completed: 128 + the signal, as shells report it, reports written.
        EXPECT_EQ(run.wait(), 128 + sig) << run.output();
        const std::string said = sig == SIGINT ? "interrupted by SIGINT" : "interrupted by SIGTERM";
        EXPECT_THAT(run.output(), HasSubstr(said));
        std::stringstream text;
        text << std::ifstream(json).rdbuf();
        EXPECT_THAT(text.str(), HasSubstr(said)) << json;
    }
    std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace mbstorm
