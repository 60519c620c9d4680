// The target's life on its own (netfuzz/target_care.hpp), against slaves scripted here: the
// sentinels armed only when wanted, a target that never comes back named with the flag to
// change, a restart charged to its root cause, a whole-server hang waited out.
#include "netfuzz/target_care.hpp"

#include <gtest/gtest.h>

#include <memory>
#include <optional>
#include <string>

#include "codec/limits.hpp"
#include "codec/mbap.hpp"
#include "net/socket.hpp"
#include "netfuzz/link.hpp"
#include "thread_slave.hpp"

namespace mbstorm::netfuzz {
namespace {

using mbstorm::test::send_bytes;
using mbstorm::test::SlaveBytes;
using mbstorm::test::ThreadSlave;

// Answers FC 03 with one register, anything else with exception 01.
void answer_reads(int fd, SlaveBytes& buf) {
    while (buf.size() >= codec::limits::kMbapHeader + 1) {
        const std::size_t whole = codec::announced_adu_size(buf.data());
        if (buf.size() < whole) return;
        const SlaveBytes r(buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(whole));
        buf.erase(buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(whole));
        if (r[7] == 0x03)
            send_bytes(fd, {r[0], r[1], 0, 0, 0, 5, r[6], 0x03, 2, 0, 0});
        else
            send_bytes(fd,
                       {r[0], r[1], 0, 0, 0, 3, r[6], static_cast<std::uint8_t>(r[7] | 0x80), 1});
    }
}

// A campaign's options and result around one target, and the care of it.
struct Cared {
    CampaignOptions options;
    CampaignResult result;
    int downs = 0;
    std::optional<TargetCare> care;
    explicit Cared(const std::string& endpoint, bool death_watch = true) {
        net::Endpoint e = *net::parse_endpoint(endpoint, 502);
        options.connector = std::make_shared<TcpConnector>(e);
        options.timeout_ms = 300;
        options.restart_wait_ms = 400;
        options.death_watch = death_watch;
        result.profile.unit = 1;
        result.profile.probe_pdu = {0x03, 0, 0, 0, 1};
        care.emplace(options, result, [this] { ++downs; });
    }
};

TEST(TargetCare, SentinelsAreArmedOnlyWhenWanted) {
    ThreadSlave slave(answer_reads);
    Cared on(slave.endpoint());
    EXPECT_EQ(on.care->arm_watch(), TargetCare::Sentinels::Armed);
    EXPECT_NE(on.care->watch(), nullptr);
    EXPECT_TRUE(on.result.death_watch);
    EXPECT_FALSE(on.care->watch_saw_death(0));
    DeviceModel model;
    model.table(codec::Table::HoldingRegisters).ranges = {{0, 9}};
    EXPECT_FALSE(on.care->arm_marker(model)) << "the sentinels watch already";

    Cared off(slave.endpoint(), false);
    EXPECT_EQ(off.care->arm_watch(), TargetCare::Sentinels::NotWanted);
    EXPECT_EQ(off.care->watch(), nullptr);
    EXPECT_FALSE(off.result.death_watch);
}

TEST(TargetCare, ATargetThatNeverComesBackIsNamedWithTheFlagToChange) {
    std::string endpoint;
    {
        ThreadSlave gone(answer_reads);
        endpoint = gone.endpoint();
    }
    Cared c(endpoint);
    EXPECT_FALSE(c.care->recover("crash:target-down/fc10"));
    EXPECT_FALSE(c.care->up());
    EXPECT_EQ(c.downs, 1);
    EXPECT_TRUE(c.result.target_lost);
    EXPECT_NE(c.result.stop_reason.find("within 400 ms (--restart-wait; no --restart-cmd given)"),
              std::string::npos)
        << c.result.stop_reason;
    EXPECT_EQ(c.result.restarts, 0u);
    EXPECT_EQ(c.care->charged("crash:target-down/fc10"), 0u);
}

TEST(TargetCare, ARestartIsChargedToItsRootCause) {
    ThreadSlave slave(answer_reads);
    Cared c(slave.endpoint());
    c.options.restart_cmd = "true";
    Execution crashed;
    crashed.target_down = true;
    EXPECT_TRUE(c.care->bring_back(crashed, "crash:target-down/fc10"));
    EXPECT_TRUE(c.care->up());
    EXPECT_EQ(c.result.deaths, 1u);
    EXPECT_EQ(c.result.restarts, 1u);
    EXPECT_EQ(c.care->charged("crash:target-down/fc10"), 1u);
    EXPECT_TRUE(c.care->recover(""));
    EXPECT_EQ(c.result.restarts, 2u);
    EXPECT_EQ(c.care->charges().size(), 1u) << "a restart for no cause is charged to none";
    // Blamed on the wrong request first: the restart follows the crash to its own key.
    c.care->move_charges("crash:target-down/fc10", "crash:target-down/fc06");
    EXPECT_EQ(c.care->charged("crash:target-down/fc10"), 0u);
    EXPECT_EQ(c.care->charged("crash:target-down/fc06"), 1u);
    c.care->charge("crash:target-down/fc01");
    c.care->move_charges("crash:target-down/fc01", "crash:target-down/fc06");
    EXPECT_EQ(c.care->charged("crash:target-down/fc06"), 2u);
}

TEST(TargetCare, AWholeServerHangThatEndsIsWaitedOutNotRestarted) {
    ThreadSlave slave(answer_reads);
    Cared c(slave.endpoint());
    Execution hung;
    hung.verdict.oracle = Oracle::Hang;
    hung.verdict.rule = std::string(kWholeServerHangRule) + "(partial-frame)";
    EXPECT_TRUE(whole_server_hang(hung.verdict));
    EXPECT_TRUE(c.care->bring_back(hung, "hang:whole-server-hang(partial-frame)"));
    EXPECT_FALSE(c.care->settle_restarted());
    EXPECT_EQ(c.result.deaths, 0u);
    EXPECT_EQ(c.result.restarts, 0u);
    EXPECT_EQ(c.downs, 1);
    Execution one_request;
    one_request.verdict.oracle = Oracle::Hang;
    one_request.verdict.rule = "no-answer/fc07";
    EXPECT_TRUE(c.care->bring_back(one_request, "hang:no-answer/fc07"));
    EXPECT_EQ(c.downs, 1) << "a hang of one request leaves the target as it is";
}

}  // namespace
}  // namespace mbstorm::netfuzz
