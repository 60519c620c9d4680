// The event-source seam: the same operations give the same completions on io_uring and on
// epoll (EpollReactor), so the workers above cannot tell which one runs them.
#include "net/event_loop.hpp"

#include <gtest/gtest.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <string>
#include <vector>

#include "net/clock.hpp"
#include "net/features.hpp"
#include "net/socket.hpp"

namespace mbstorm::net {
namespace {

// io_uring where this process may use it (not under a filter that refuses it), epoll always.
std::vector<Backend> backends_here() {
    std::vector<Backend> out{Backend::Epoll};
    if (features().ring && features().buf_ring && features().multishot_recv &&
        features().multishot_accept)
        out.push_back(Backend::IoUring);
    return out;
}

class EventLoopTest : public ::testing::TestWithParam<Backend> {
  protected:
    void SetUp() override {
        ASSERT_TRUE(loop.init(GetParam(), RingOptions{}).ok());
        ASSERT_TRUE(loop.init_buffers(3, 4, 8).ok());  // four 8-byte buffers
    }

    // Waits up to a second for `count` completions in all.
    std::vector<Completion> wait_for(std::size_t count) {
        const std::int64_t deadline = now_ns() + kNsPerSec;
        while (seen.size() < count && now_ns() < deadline) {
            loop.submit_and_wait(1, 10 * kNsPerMs);
            loop.drain([this](const Completion& c) { seen.push_back(c); });
        }
        return seen;
    }

    const Completion* find(std::uint64_t user_data) const {
        for (const Completion& c : seen)
            if (c.user_data == user_data) return &c;
        return nullptr;
    }

    static std::pair<UniqueFd, UniqueFd> stream_pair() {
        int sv[2];
        EXPECT_EQ(::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv), 0);
        return {UniqueFd(sv[0]), UniqueFd(sv[1])};
    }

    EventLoop loop;
    std::vector<Completion> seen;
};

TEST_P(EventLoopTest, AMultishotRecvReportsEachArrivalInAProvidedBufferUntilThePeerCloses) {
    auto [ours, theirs] = stream_pair();
    ASSERT_TRUE(loop.recv(ours.get(), 7, /*multishot=*/true));
    ASSERT_EQ(::write(theirs.get(), "hello", 5), 5);
    ASSERT_EQ(wait_for(1).size(), 1u);
    const Completion first = seen[0];
    EXPECT_EQ(first.user_data, 7u);
    ASSERT_EQ(first.res, 5);
    ASSERT_TRUE(BufRing::has_buffer(first.flags));
    EXPECT_NE(first.flags & IORING_CQE_F_MORE, 0u);
    const std::uint16_t id = BufRing::buffer_id(first.flags);
    EXPECT_EQ(std::string(reinterpret_cast<char*>(loop.buffer(id)), 5), "hello");
    loop.recycle(id);
    theirs.reset();
    ASSERT_EQ(wait_for(2).size(), 2u);
    EXPECT_EQ(seen[1].user_data, 7u);
    EXPECT_EQ(seen[1].res, 0);
    EXPECT_EQ(seen[1].flags & IORING_CQE_F_MORE, 0u);
}

TEST_P(EventLoopTest, DataAndTheEndOfStreamArrivingTogetherAreBothReported) {
    auto [ours, theirs] = stream_pair();
    ASSERT_TRUE(loop.recv(ours.get(), 7, true));
    loop.submit_and_wait(0, 0);  // armed, nothing to read yet
    loop.drain([this](const Completion& c) { seen.push_back(c); });
    ASSERT_TRUE(seen.empty());
    ASSERT_EQ(::write(theirs.get(), "bye", 3), 3);
    theirs.reset();  // a request and a half-close in one wake-up
    ASSERT_EQ(wait_for(2).size(), 2u);
    EXPECT_EQ(seen[0].res, 3);
    EXPECT_EQ(seen[1].res, 0);
    EXPECT_EQ(seen[1].flags & IORING_CQE_F_MORE, 0u);
}

TEST_P(EventLoopTest, ARecvEndsWithNoBuffersWhenThePoolRunsDry) {
    auto [ours, theirs] = stream_pair();
    ASSERT_TRUE(loop.recv(ours.get(), 9, true));
    const std::string data(40, 'x');  // five buffers' worth; none is given back
    ASSERT_EQ(::write(theirs.get(), data.data(), data.size()), 40);
    wait_for(5);
    ASSERT_EQ(seen.size(), 5u);
    for (std::size_t i = 0; i < 4; ++i) EXPECT_EQ(seen[i].res, 8) << i;
    EXPECT_EQ(seen[4].res, -ENOBUFS);
    EXPECT_EQ(seen[4].flags & IORING_CQE_F_MORE, 0u);
}

TEST_P(EventLoopTest, ASendCompletesWithTheBytesThePeerReads) {
    auto [ours, theirs] = stream_pair();
    static const char kData[] = "request";
    ASSERT_TRUE(loop.send(ours.get(), kData, 7, 11));
    ASSERT_EQ(wait_for(1).size(), 1u);
    EXPECT_EQ(seen[0].user_data, 11u);
    EXPECT_EQ(seen[0].res, 7);
    char got[8] = {};
    ASSERT_EQ(::read(theirs.get(), got, sizeof got), 7);
    EXPECT_STREQ(got, "request");
}

TEST_P(EventLoopTest, AMultishotAcceptReportsEveryConnection) {
    Endpoint ep = *parse_endpoint("127.0.0.1:0");
    UniqueFd listener = listen_socket(ep, ListenOptions{16, false, true}).value();
    ep.set_port(local_port(listener.get()));
    ASSERT_TRUE(loop.accept(listener.get(), 5, true));
    UniqueFd a(connect_blocking(ep)), b(connect_blocking(ep));
    ASSERT_EQ(wait_for(2).size(), 2u);
    for (const Completion& c : seen) {
        EXPECT_EQ(c.user_data, 5u);
        EXPECT_GE(c.res, 0);
        EXPECT_NE(c.flags & IORING_CQE_F_MORE, 0u);
        loop.close(c.res);
    }
}

TEST_P(EventLoopTest, ARefusedConnectEndsWithItsErrorAndCancelsItsTimeout) {
    Endpoint ep = *parse_endpoint("127.0.0.1:0");
    {
        UniqueFd closed = listen_socket(ep, ListenOptions{16, false, true}).value();
        ep.set_port(local_port(closed.get()));
    }  // nothing listens there now
    const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    __kernel_timespec timeout{1, 0};
    ASSERT_TRUE(loop.connect(fd, ep.sa(), ep.len, 1, &timeout, 2));
    wait_for(2);
    ASSERT_NE(find(1), nullptr);
    ASSERT_NE(find(2), nullptr);
    EXPECT_EQ(find(1)->res, -ECONNREFUSED);
    EXPECT_EQ(find(2)->res, -ECANCELED);
    loop.close(fd);
}

TEST_P(EventLoopTest, AConnectNobodyAnswersEndsAtItsTimeout) {
    // A listener whose accept queue is full drops the SYNs of further connects.
    Endpoint ep = *parse_endpoint("127.0.0.1:0");
    UniqueFd listener = listen_socket(ep, ListenOptions{0, false, true}).value();
    ep.set_port(local_port(listener.get()));
    std::vector<UniqueFd> fillers;
    for (int i = 0; i < 4; ++i) fillers.emplace_back(connect_nonblocking(ep));
    ::usleep(50'000);
    const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    __kernel_timespec timeout{0, 100'000'000};
    const std::int64_t start = now_ns();
    ASSERT_TRUE(loop.connect(fd, ep.sa(), ep.len, 1, &timeout, 2));
    wait_for(2);
    ASSERT_NE(find(1), nullptr);
    ASSERT_NE(find(2), nullptr);
    EXPECT_EQ(find(1)->res, -ECANCELED);
    EXPECT_EQ(find(2)->res, -ETIME);
    EXPECT_GE(now_ns() - start, 100 * kNsPerMs);  // not before its time
    loop.close(fd);
}

TEST_P(EventLoopTest, ACancelledRecvEndsCancelledAndTheCancelSucceeds) {
    auto [ours, theirs] = stream_pair();
    ASSERT_TRUE(loop.recv(ours.get(), 3, true));
    loop.submit_and_wait(0, 0);  // armed (and found nothing to read)
    loop.drain([this](const Completion& c) { seen.push_back(c); });
    ASSERT_TRUE(seen.empty());
    ASSERT_TRUE(loop.cancel_input(ours.get(), 3, 4));
    wait_for(2);
    ASSERT_NE(find(3), nullptr);
    ASSERT_NE(find(4), nullptr);
    EXPECT_EQ(find(3)->res, -ECANCELED);
    EXPECT_EQ(find(3)->flags & IORING_CQE_F_MORE, 0u);
    EXPECT_EQ(find(4)->res, 0);
}

TEST_P(EventLoopTest, ATimeoutFiresNoSoonerThanAsked) {
    __kernel_timespec after{0, 30'000'000};
    const std::int64_t start = now_ns();
    ASSERT_TRUE(loop.timeout(&after, 8));
    ASSERT_EQ(wait_for(1).size(), 1u);
    EXPECT_EQ(seen[0].user_data, 8u);
    EXPECT_EQ(seen[0].res, -ETIME);
    EXPECT_GE(now_ns() - start, 30 * kNsPerMs);
}

TEST_P(EventLoopTest, ShutdownAndCloseEndsThePendingRecv) {
    auto [ours, theirs] = stream_pair();
    const int fd = ours.release();
    ASSERT_TRUE(loop.recv(fd, 6, true));
    loop.submit_and_wait(0, 0);
    loop.drain([this](const Completion& c) { seen.push_back(c); });
    loop.shutdown_and_close(fd);
    ASSERT_EQ(wait_for(1).size(), 1u);
    EXPECT_EQ(seen[0].user_data, 6u);
    EXPECT_LE(seen[0].res, 0);  // end of stream (io_uring) or cancelled (epoll)
    EXPECT_EQ(seen[0].flags & IORING_CQE_F_MORE, 0u);
}

std::string backend_label(const ::testing::TestParamInfo<Backend>& info) {
    return info.param == Backend::IoUring ? "IoUring" : "Epoll";
}

INSTANTIATE_TEST_SUITE_P(Backends, EventLoopTest, ::testing::ValuesIn(backends_here()),
                         backend_label);

TEST(Backend, AutoFallsBackToEpollOnlyWhenIoUringIsRefusedAndSaysWhy) {
    Result<BackendDecision> chosen = choose_backend(BackendChoice::Auto, true);
    ASSERT_TRUE(chosen.ok());
    BackendDecision decision = *chosen;
    if (features().ring && features().buf_ring) {
        EXPECT_EQ(decision.backend, Backend::IoUring);
        EXPECT_TRUE(decision.why.empty());
    } else {
        EXPECT_EQ(decision.backend, Backend::Epoll);
        EXPECT_NE(decision.why.find("io_uring"), std::string::npos) << decision.why;
    }
    chosen = choose_backend(BackendChoice::Epoll, true);
    ASSERT_TRUE(chosen.ok());
    decision = *chosen;
    EXPECT_EQ(decision.backend, Backend::Epoll);
    EXPECT_TRUE(decision.why.empty());
}

TEST(Backend, AskingForIoUringWhereItIsRefusedFailsNamingTheCause) {
    const Result<BackendDecision> chosen = choose_backend(BackendChoice::IoUring, false);
    EXPECT_EQ(chosen.ok(), features().ring);
    if (!features().ring) {
        EXPECT_EQ(chosen.error().code(), ErrorCode::Unsupported);
        EXPECT_NE(chosen.error().text().find("io_uring_setup refused"), std::string::npos)
            << chosen.error().text();
    }
}

TEST(Backend, ChoicesParseByTheirNames) {
    BackendChoice c{};
    EXPECT_TRUE(parse_backend_choice("epoll", c));
    EXPECT_EQ(c, BackendChoice::Epoll);
    EXPECT_TRUE(parse_backend_choice("io_uring", c));
    EXPECT_EQ(c, BackendChoice::IoUring);
    EXPECT_TRUE(parse_backend_choice("auto", c));
    EXPECT_EQ(c, BackendChoice::Auto);
    EXPECT_FALSE(parse_backend_choice("kqueue", c));
}

}  // namespace
}  // namespace mbstorm::net
