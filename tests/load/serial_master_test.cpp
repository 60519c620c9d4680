// SerialMaster on a pseudo-terminal: the test plays the slave on the pty's master side and
// answers with what each case needs (a good frame, a bad CRC, another unit, nothing).
#include <fcntl.h>
#include <gtest/gtest.h>
#include <pty.h>
#include <unistd.h>

#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include "codec/rtu.hpp"
#include "load/serial_master.hpp"

using namespace mbstorm;

namespace {

std::vector<std::uint8_t> rtu(std::uint8_t unit, std::vector<std::uint8_t> pdu) {
    std::vector<std::uint8_t> out(pdu.size() + 3);
    out.resize(codec::encode_rtu_frame(unit, pdu, out).size);
    return out;
}

class SerialMasterTest : public ::testing::Test {
  protected:
    struct SerialOutcomeResult {
        load::SerialOutcome outcome{};
        codec::Bytes response;
        std::int64_t sent_ns = 0;
    };
    void SetUp() override {
        int slave = -1;
        char name[128] = {};
        ASSERT_EQ(::openpty(&pty_, &slave, name, nullptr, nullptr), 0);
        ::close(slave);
        net::SerialSettings line;
        line.parity = net::Parity::None;
        ASSERT_EQ(master_.open(name, line, codec::Framing::Rtu), Error::none());
        master_.turnaround_ns = 1'000'000;
    }
    void TearDown() override {
        if (slave_.joinable()) slave_.join();
        ::close(pty_);
    }
    // A slave that waits for one request (bounded: 5 s) and answers `answer` (if any).
    void answer_with(std::vector<std::uint8_t> answer) {
        slave_ = std::thread([this, answer] {
            std::uint8_t buf[256];
            const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
            ssize_t got = 0;
            while (got <= 0 && std::chrono::steady_clock::now() < deadline) {
                got = ::read(pty_, buf, sizeof buf);
                if (got <= 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
            }
            request_.assign(buf, buf + (got > 0 ? got : 0));
            if (!answer.empty()) (void)!::write(pty_, answer.data(), answer.size());
        });
    }
    SerialOutcomeResult run(std::uint8_t unit, std::int64_t timeout_ns = 2'000'000'000) {
        const std::vector<std::uint8_t> pdu{0x03, 0x00, 0x01, 0x00, 0x01};
        SerialOutcomeResult r;
        r.outcome = master_.transact(unit, pdu, timeout_ns, r.response, r.sent_ns);
        return r;
    }

    int pty_ = -1;
    load::SerialMaster master_;
    std::thread slave_;
    std::vector<std::uint8_t> request_;
};

TEST_F(SerialMasterTest, AnswerIsReturnedAsItsPdu) {
    answer_with(rtu(1, {0x03, 0x02, 0xAB, 0xCD}));
    auto r = run(1);
    ASSERT_EQ(r.outcome, load::SerialOutcome::Answered);
    EXPECT_EQ(std::vector<std::uint8_t>(r.response.begin(), r.response.end()),
              (std::vector<std::uint8_t>{0x03, 0x02, 0xAB, 0xCD}));
    slave_.join();
    EXPECT_EQ(request_, rtu(1, {0x03, 0x00, 0x01, 0x00, 0x01}));
}

TEST_F(SerialMasterTest, BadCrcIsItsOwnOutcome) {
    auto bad = rtu(1, {0x03, 0x02, 0xAB, 0xCD});
    bad.back() ^= 0x01;
    answer_with(bad);
    EXPECT_EQ(run(1).outcome, load::SerialOutcome::BadCheck);
}

TEST_F(SerialMasterTest, AnswerFromAnotherUnitIsNotTaken) {
    answer_with(rtu(2, {0x03, 0x02, 0xAB, 0xCD}));
    EXPECT_EQ(run(1).outcome, load::SerialOutcome::WrongUnit);
}

TEST_F(SerialMasterTest, SilenceIsATimeout) {
    answer_with({});
    EXPECT_EQ(run(1, 100'000'000).outcome, load::SerialOutcome::Timeout);
}

TEST_F(SerialMasterTest, BroadcastExpectsNoAnswer) {
    answer_with({});
    EXPECT_EQ(run(0).outcome, load::SerialOutcome::Broadcast);
}

}  // namespace
