// Discovery against slaves scripted here: whether a target drops what is pipelined behind an
// exception is asked with three requests behind it, so that one drop of a lossy target landing
// there is not taken for a target that flushes after exceptions (which would have every later
// case sent one request at a time and its random drops blamed on exceptions).
#include <gtest/gtest.h>

#include <atomic>
#include <memory>
#include <string>
#include <utility>

#include "codec/limits.hpp"
#include "codec/mbap.hpp"
#include "codec/pdu.hpp"
#include "net/socket.hpp"
#include "netfuzz/discovery.hpp"
#include "netfuzz/link.hpp"
#include "thread_slave.hpp"

namespace mbstorm::netfuzz {
namespace {

using mbstorm::test::send_bytes;
using mbstorm::test::SlaveBytes;
using mbstorm::test::ThreadSlave;

// What the scripted slave does with the requests behind an exception.
enum class AfterException {
    AnswersThem,  // a conforming slave
    // A lossy link whose one drop happened to land right behind the exception discovery asks
    // about (to an undefined function code): the request after the first one is lost.
    DropsOneOnce,
    FlushesThem,  // libmodbus: what it has read after an exception is discarded
};

// Answers FC 03 with one register, anything else with exception 01.
ThreadSlave::Consume slave_that(AfterException after) {
    auto dropped = std::make_shared<std::atomic<bool>>(false);
    return [after, dropped](int fd, SlaveBytes& buf) {
        bool flushing = false, drop_next = false;
        while (buf.size() >= codec::limits::kMbapHeader + 1) {
            const std::size_t whole = codec::announced_adu_size(buf.data());
            if (buf.size() < whole) return;
            const SlaveBytes r(buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(whole));
            buf.erase(buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(whole));
            if (flushing || std::exchange(drop_next, false)) continue;
            const std::uint8_t fc = r[7];
            if (fc == 0x03) {
                send_bytes(fd, {r[0], r[1], 0, 0, 0, 5, r[6], fc, 2, 0, 0});
                continue;
            }
            send_bytes(fd, {r[0], r[1], 0, 0, 0, 3, r[6], static_cast<std::uint8_t>(fc | 0x80), 1});
            flushing = after == AfterException::FlushesThem;
            drop_next =
                after == AfterException::DropsOneOnce && fc == 0x41 && !dropped->exchange(true);
        }
    };
}

TargetProfile discover(ThreadSlave& slave) {
    net::Endpoint e = *net::parse_endpoint(slave.endpoint(), 502);
    TcpConnector connector(e);
    TargetProfile profile;
    const Error error = discover_target(connector, 1, 300, profile);
    EXPECT_TRUE(error.ok()) << error.text();
    return profile;
}

TEST(Discovery, OneDropLandingBehindAnExceptionIsNotATargetThatDropsAfterExceptions) {
    ThreadSlave slave(slave_that(AfterException::DropsOneOnce));
    EXPECT_FALSE(discover(slave).drops_after_exception);
}

TEST(Discovery, ATargetThatFlushesItsInputAfterAnExceptionIsKnownSo) {
    ThreadSlave slave(slave_that(AfterException::FlushesThem));
    EXPECT_TRUE(discover(slave).drops_after_exception);
}

TEST(Discovery, AConformingTargetKeepsWhatFollowsAnException) {
    ThreadSlave slave(slave_that(AfterException::AnswersThem));
    const TargetProfile p = discover(slave);
    EXPECT_FALSE(p.drops_after_exception);
    EXPECT_EQ(p.probe_pdu.at(0), 0x03);
    EXPECT_TRUE(p.unsupported[0x41]);
}

// Discovery's requests, one per public code: valid (the codec decodes each), and these bytes,
// so a target's recorded answers and saved findings keep meaning the same requests.
TEST(Discovery, CanonicalRequestsAreValidAndStable) {
    const std::vector<std::vector<std::uint8_t>> expected = {
        {0x01, 0, 0, 0, 1},
        {0x02, 0, 0, 0, 1},
        {0x03, 0, 0, 0, 1},
        {0x04, 0, 0, 0, 1},
        {0x05, 0x5F, 0xFF, 0xFF, 0x00},
        {0x06, 0x5F, 0xFF, 0, 0},
        {0x07},
        {0x08, 0, 0, 0x12, 0x34},
        {0x0B},
        {0x0C},
        {0x0F, 0x5F, 0xFF, 0, 1, 1, 0},
        {0x10, 0x5F, 0xFF, 0, 1, 2, 0, 0},
        {0x11},
        {0x14, 7, 6, 0, 1, 0, 0, 0, 1},
        {0x15, 9, 6, 0, 1, 0, 0, 0, 1, 0, 0},
        {0x16, 0x5F, 0xFF, 0xFF, 0xFF, 0, 0},
        {0x17, 0, 0, 0, 1, 0x5F, 0xFF, 0, 1, 2, 0, 0},
        {0x18, 0x5F, 0xFF},
        {0x2B, 0x0E, 0x01, 0x00},
    };
    ASSERT_EQ(canonical_requests().size(), expected.size());
    for (std::size_t i = 0; i < expected.size(); ++i) {
        const std::vector<std::uint8_t>& pdu = canonical_requests()[i];
        EXPECT_EQ(pdu, expected[i]) << "function 0x" << std::hex << int{expected[i][0]};
        codec::Request decoded;
        EXPECT_TRUE(codec::decode_request(pdu, decoded).ok()) << int{expected[i][0]};
    }
}

}  // namespace
}  // namespace mbstorm::netfuzz
