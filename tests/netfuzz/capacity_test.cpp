// The capacity check against slaves scripted here: a lossy target that drops one request in
// seven, whatever connection it came on, holds every connection it is given (its silent probes
// are asked again); a target that stops serving the connections it accepts beyond 20 is the
// unserved-connections hang however often they are asked.
#include <gtest/gtest.h>

#include <atomic>
#include <memory>
#include <mutex>
#include <set>
#include <string>

#include "codec/limits.hpp"
#include "codec/mbap.hpp"
#include "net/socket.hpp"
#include "netfuzz/capacity.hpp"
#include "netfuzz/link.hpp"
#include "netfuzz/rules.hpp"
#include "thread_slave.hpp"

namespace mbstorm::netfuzz {
namespace {

using mbstorm::test::send_bytes;
using mbstorm::test::SlaveBytes;
using mbstorm::test::ThreadSlave;

const SlaveBytes kProbe = {0x03, 0x00, 0x00, 0x00, 0x01};

// Answers every whole request with one register, but those `answers` says no to.
ThreadSlave::Consume slave_answering(std::function<bool(int fd)> answers) {
    return [answers = std::move(answers)](int fd, SlaveBytes& buf) {
        while (buf.size() >= codec::limits::kMbapHeader + 1) {
            const std::size_t whole = codec::announced_adu_size(buf.data());
            if (buf.size() < whole) return;
            const SlaveBytes r(buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(whole));
            buf.erase(buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(whole));
            if (answers(fd)) send_bytes(fd, {r[0], r[1], 0, 0, 0, 5, r[6], r[7], 2, 0, 0});
        }
    };
}

CapacityResult check(ThreadSlave& slave, std::uint32_t connections) {
    net::Endpoint e = *net::parse_endpoint(slave.endpoint(), 502);
    TcpConnector connector(e);
    TargetProfile profile;
    profile.probe_pdu = kProbe;
    return check_capacity(connector, profile, connections, 200, 0);
}

TEST(CapacityCheck, ALossyTargetThatServesEveryConnectionHoldsThemAll) {
    auto requests = std::make_shared<std::atomic<unsigned>>(0);
    ThreadSlave slave(slave_answering([requests](int) { return ++*requests % 7 != 0; }));
    const CapacityResult r = check(slave, 256);
    EXPECT_FALSE(r.verdict) << r.verdict.summary;
    EXPECT_EQ(r.held, 256u);
    EXPECT_GT(requests->load(), 256u) << "some probes were dropped and asked again";
}

TEST(CapacityCheck, ConnectionsAcceptedAndNeverServedAreAHang) {
    auto served = std::make_shared<std::set<int>>();
    ThreadSlave slave(slave_answering([served](int fd) {
        if (served->size() < 20) served->insert(fd);
        return served->count(fd) > 0;
    }));
    const CapacityResult r = check(slave, 256);
    EXPECT_EQ(r.verdict.oracle, Oracle::Hang) << r.verdict.summary;
    EXPECT_EQ(r.verdict.rule, kCapacityUnservedRule);
    EXPECT_EQ(r.held, 16u);
}

}  // namespace
}  // namespace mbstorm::netfuzz
