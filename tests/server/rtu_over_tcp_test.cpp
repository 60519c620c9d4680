// The reference slave speaking RTU over TCP (ServerConfig::framing = Rtu): RTU frames on the
// stream, answers in order, exceptions as RTU frames; a frame with a bad CRC dropped and the
// next one answered, as a serial slave behind a gateway does (counted as a CRC error), and a
// write to unit 0 carried out and not answered (a broadcast).
#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "client_test_support.hpp"
#include "codec/rtu.hpp"
#include "server/server.hpp"
#include "server/stats.hpp"

using namespace mbstorm;
using test::Client;

namespace {

using Frame = std::vector<std::uint8_t>;

Frame with_crc(Frame f) {
    const std::uint16_t crc = codec::crc16(codec::Bytes(f.data(), f.size()));
    f.push_back(static_cast<std::uint8_t>(crc & 0xFF));
    f.push_back(static_cast<std::uint8_t>(crc >> 8));
    return f;
}

std::unique_ptr<server::Server> start_rtu() {
    server::ServerConfig config = test::test_config();
    config.framing = codec::Framing::Rtu;
    auto s = std::make_unique<server::Server>(std::move(config));
    const Error error = s->start();
    EXPECT_TRUE(error.ok()) << error.text();
    return s;
}

// FC03 x `quantity` from 0 on unit 1; its answer is 5 + 2 * quantity bytes.
Frame rtu_read_holding(std::uint8_t quantity) {
    return with_crc({1, 3, 0, 0, 0, quantity});
}

void expect_read_answer(const Frame& a, std::uint8_t quantity) {
    ASSERT_EQ(a.size(), 5u + 2u * quantity);
    EXPECT_EQ(a[0], 1);
    EXPECT_EQ(a[1], 3);
    EXPECT_EQ(a[2], 2 * quantity);
    codec::RtuFrame f;
    EXPECT_EQ(codec::decode_rtu_frame(codec::Bytes(a.data(), a.size()), f), codec::CodecError::Ok);
}

}  // namespace

TEST(RtuOverTcp, AnswersPipelinedAndFragmentedRequestsInOrder) {
    auto srv = start_rtu();
    Client c(*srv);
    Frame burst;
    for (std::uint8_t q = 1; q <= 5; ++q) {
        const Frame f = rtu_read_holding(q);
        burst.insert(burst.end(), f.begin(), f.end());
    }
    ASSERT_TRUE(c.send_all(burst));
    for (std::uint8_t q = 1; q <= 5; ++q) expect_read_answer(c.recv_n(5u + 2u * q), q);
    // Byte by byte.
    const Frame one = rtu_read_holding(2);
    for (std::uint8_t b : one) ASSERT_TRUE(c.send_all(&b, 1));
    expect_read_answer(c.recv_n(9), 2);
    EXPECT_EQ(srv->stats().transactions, 6u);
}

TEST(RtuOverTcp, ExceptionsAreRtuFrames) {
    auto srv = start_rtu();
    Client c(*srv);
    // Quantity 0 is illegal (exception 03); an unknown function code gets 01.
    ASSERT_TRUE(c.send_all(with_crc({1, 3, 0, 0, 0, 0})));
    EXPECT_EQ(c.recv_n(5), with_crc({1, 0x83, 3}));
    ASSERT_TRUE(c.send_all(with_crc({1, 0x41, 0x12})));
    EXPECT_EQ(c.recv_n(5), with_crc({1, 0xC1, 1}));
}

// A serial slave drops a frame whose CRC fails and listens on; the gateway keeps its TCP link.
// The length rule of the frame's function code says where it ends. (Before, the connection
// was closed, and a gateway's link with it.)
TEST(RtuOverTcp, AFrameWithABadCrcIsDroppedAndTheNextOneAnswered) {
    auto srv = start_rtu();
    Client c(*srv);
    Frame stream = rtu_read_holding(1);
    Frame broken = rtu_read_holding(4);
    broken.back() ^= 0xFF;
    stream.insert(stream.end(), broken.begin(), broken.end());
    const Frame after = rtu_read_holding(2);
    stream.insert(stream.end(), after.begin(), after.end());
    ASSERT_TRUE(c.send_all(stream));
    expect_read_answer(c.recv_n(7), 1);
    expect_read_answer(c.recv_n(9), 2);
    EXPECT_TRUE(test::eventually([&] { return srv->stats().crc_errors == 1; }));
    EXPECT_EQ(srv->stats().transactions, 2u);
    ASSERT_TRUE(c.send_all(rtu_read_holding(3)));
    expect_read_answer(c.recv_n(11), 3);
}

// A frame of an unknown function code has no length rule: with its CRC wrong, nothing says
// where the next frame starts, and the link is closed once no CRC ends the bytes within the
// longest RTU frame.
TEST(RtuOverTcp, ABadFrameWithNoLengthRuleClosesTheLink) {
    auto srv = start_rtu();
    Client c(*srv);
    Frame garbage = {1, 0x41};
    for (int i = 0; i < 300; ++i) garbage.push_back(static_cast<std::uint8_t>(i * 7 + 1));
    ASSERT_TRUE(c.send_all(garbage));
    EXPECT_TRUE(c.closed_by_peer());
    EXPECT_TRUE(test::eventually([&] { return srv->stats().crc_errors == 1; }));
}

// Unit 0 on a serial line is a broadcast: every slave carries out the write, none answers.
TEST(RtuOverTcp, AWriteToUnitZeroIsCarriedOutAndNotAnswered) {
    auto srv = start_rtu();
    Client c(*srv);
    ASSERT_TRUE(c.send_all(with_crc({0, 6, 0, 5, 0x12, 0x34})));
    ASSERT_TRUE(c.send_all(with_crc({1, 3, 0, 5, 0, 1})));
    // The first bytes back are the read's: the write drew no echo.
    EXPECT_EQ(c.recv_n(7), with_crc({1, 3, 2, 0x12, 0x34}));
    EXPECT_TRUE(c.silent_for(100));
}

TEST(RtuOverTcp, MbapOnAnRtuPortIsNotAnswered) {
    auto srv = start_rtu();
    Client c(*srv);
    // An MBAP read: to an RTU reader, address 0x00 with function 0x01 and a wrong CRC
    // (dropped), then the start of a frame of function 0x00 (no length rule: more awaited).
    ASSERT_TRUE(c.send_all(test::read_holding(1, 1, 0, 10)));
    EXPECT_TRUE(c.silent_for(300));
    EXPECT_EQ(srv->stats().transactions, 0u);
}
