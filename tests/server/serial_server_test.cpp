// The serial server on a pseudo-terminal: a test plays the master on the pty's master side.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <pty.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include "client_test_support.hpp"
#include "codec/ascii.hpp"
#include "codec/rtu.hpp"
#include "net/clock.hpp"
#include "net/serial_port.hpp"
#include "server/serial_server.hpp"
#include "slave/data_model.hpp"

using namespace mbstorm;

namespace {

struct PtyPair {
    int master = -1;
    std::string slave_path;
    PtyPair() {
        int slave = -1;
        char name[128] = {};
        if (::openpty(&master, &slave, name, nullptr, nullptr) == 0) {
            slave_path = name;
            ::close(slave);  // the server opens it by name
        }
    }
    ~PtyPair() {
        if (master >= 0) ::close(master);
    }
};

std::vector<std::uint8_t> rtu(std::uint8_t unit, std::vector<std::uint8_t> pdu) {
    std::vector<std::uint8_t> out(pdu.size() + 3);
    auto r = codec::encode_rtu_frame(unit, pdu, out);
    out.resize(r.size);
    return out;
}

// What the master side reads within `timeout_ms` (bounded: stops at `want` bytes).
std::vector<std::uint8_t> read_for(int fd, std::size_t want, int timeout_ms) {
    std::vector<std::uint8_t> got;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
    while (got.size() < want && std::chrono::steady_clock::now() < deadline) {
        std::uint8_t buf[512];
        ssize_t n = ::read(fd, buf, sizeof buf);
        if (n > 0)
            got.insert(got.end(), buf, buf + n);
        else
            std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    return got;
}

class SerialServerTest : public ::testing::Test {
  protected:
    void start(codec::Framing framing, slave::FaultConfig faults = {}) {
        ASSERT_GE(pty.master, 0);
        int flags = ::fcntl(pty.master, F_GETFL);
        ::fcntl(pty.master, F_SETFL, flags | O_NONBLOCK);
        units.model_at(0).holding_registers().set(5, 0x1234);
        units.broadcast_unit_zero = true;
        units.unknown_unit_policy = slave::UnknownUnitPolicy::Ignore;
        server::SerialServerConfig c;
        c.device = pty.slave_path;
        c.line.baud = 19200;
        c.framing = framing;
        c.units = &units;
        c.only_unit = 1;
        c.faults = faults;
        server_ = std::make_unique<server::SerialServer>(c);
        const Error opened = server_->open();
        ASSERT_TRUE(opened.ok()) << opened.text();
        thread_ = std::thread([this] { error_ = server_->run(stop_); });
    }
    void TearDown() override {
        stop_ = true;
        if (thread_.joinable()) thread_.join();
        EXPECT_TRUE(error_.ok()) << error_.text();
    }
    // The server counts an answer once it is written, so the master may read it first: wait
    // for the count to catch up before judging the counters.
    void wait_for_responses(std::uint64_t n) {
        EXPECT_TRUE(test::eventually([&] { return server_->stats().responses >= n; }));
    }
    void send(const std::vector<std::uint8_t>& bytes) {
        ASSERT_EQ(::write(pty.master, bytes.data(), bytes.size()),
                  static_cast<ssize_t>(bytes.size()));
    }

    PtyPair pty;
    slave::UnitModels units = slave::UnitModels::shared();
    std::unique_ptr<server::SerialServer> server_;
    std::atomic<bool> stop_{false};
    std::thread thread_;
    Error error_;
};

// The line's timing, pinned to the specification's numbers (Modbus over Serial Line v1.02,
// 2.5.1.1): t1.5 and t3.5 in characters of start + data + parity + stop bits up to 19200 baud,
// fixed at 750 us and 1.75 ms above it. (The test below measures against these functions, so
// it alone would let a wrong t3.5 through.)
TEST(SerialTiming, SilencesAreTheSpecificationsCharacterTimes) {
    net::SerialSettings line;  // 19200 8E1: 11 bits a character, 572,916 ns
    EXPECT_EQ(net::bits_per_character(line), 11u);
    EXPECT_EQ(net::character_time_ns(line), 572'916);
    EXPECT_EQ(net::intercharacter_timeout_ns(line), 859'374);
    EXPECT_EQ(net::interframe_silence_ns(line), 2'005'206);
    line.baud = 9600;
    line.parity = net::Parity::None;
    line.stop_bits = 2;                                      // 11 bits again
    EXPECT_EQ(net::interframe_silence_ns(line), 4'010'415);  // 1,145,833 ns a character
    line.baud = 38400;
    EXPECT_EQ(net::intercharacter_timeout_ns(line), 750'000);
    EXPECT_EQ(net::interframe_silence_ns(line), 1'750'000);
}

TEST_F(SerialServerTest, RtuReadIsAnsweredAfterTheInterFrameSilence) {
    start(codec::Framing::Rtu);
    const std::int64_t sent = net::now_ns();
    send(rtu(1, {0x03, 0x00, 0x05, 0x00, 0x01}));
    auto got = read_for(pty.master, 7, 5000);
    const std::int64_t elapsed = net::now_ns() - sent;
    EXPECT_EQ(got, rtu(1, {0x03, 0x02, 0x12, 0x34}));
    // 8 request characters at 19200 8E1 (11 bits) plus t3.5 is at least 2 ms... the server
    // cannot answer before the request has left the (emulated) wire and the silence passed.
    net::SerialSettings line;
    EXPECT_GE(elapsed, net::interframe_silence_ns(line));
    wait_for_responses(1);
    EXPECT_EQ(server_->stats().requests, 1u);
    EXPECT_EQ(server_->stats().responses, 1u);
}

TEST_F(SerialServerTest, RtuExceptionsBroadcastsOtherUnitsAndBadCrc) {
    start(codec::Framing::Rtu);
    // Bad CRC: ignored and counted.
    auto bad = rtu(1, {0x03, 0x00, 0x05, 0x00, 0x01});
    bad.back() ^= 0x55;
    send(bad);
    EXPECT_TRUE(read_for(pty.master, 1, 300).empty());
    // Another unit on the bus: silence.
    send(rtu(2, {0x03, 0x00, 0x05, 0x00, 0x01}));
    EXPECT_TRUE(read_for(pty.master, 1, 300).empty());
    // Broadcast write: executed (waited for by its count), not answered.
    send(rtu(0, {0x06, 0x00, 0x07, 0xBE, 0xEF}));
    EXPECT_TRUE(read_for(pty.master, 1, 300).empty());
    EXPECT_TRUE(test::eventually([&] { return server_->stats().broadcasts == 1; }));
    EXPECT_EQ(units.model_at(0).holding_registers().get(7), 0xBEEF);
    // Unsupported function: exception 01, answered.
    send(rtu(1, {0x09, 0x00}));
    EXPECT_EQ(read_for(pty.master, 5, 5000), rtu(1, {0x89, 0x01}));
    wait_for_responses(1);
    const auto s = server_->stats();
    EXPECT_EQ(s.bad_checks, 1u);
    EXPECT_EQ(s.not_addressed, 1u);
    EXPECT_EQ(s.broadcasts, 1u);
    EXPECT_EQ(s.exceptions, 1u);
}

TEST_F(SerialServerTest, FaultsAnswerLateWithAnExceptionOrNotAtAll) {
    // A fixed 150 ms delay and exception 06 for every request: the answer is late and wrong.
    slave::FaultConfig late_and_busy;
    late_and_busy.delay = {slave::DelayConfig::Kind::Fixed, 150'000'000, 0, 0, 0};
    late_and_busy.exception_rate = 1.0;
    late_and_busy.exception_code = codec::ExceptionCode::ServerDeviceBusy;
    start(codec::Framing::Rtu, late_and_busy);
    const std::int64_t sent = net::now_ns();
    send(rtu(1, {0x03, 0x00, 0x05, 0x00, 0x01}));
    EXPECT_EQ(read_for(pty.master, 5, 5000), rtu(1, {0x83, 0x06}));
    EXPECT_GE(net::now_ns() - sent, 150'000'000);
    // A broadcast is never answered, fault or not, and still executed: counted once carried
    // out, so waited for by its count (beside a busy suite the server's thread may take longer
    // than the 300 ms of silence the test listens for).
    send(rtu(0, {0x06, 0x00, 0x07, 0xBE, 0xEF}));
    EXPECT_TRUE(read_for(pty.master, 1, 300).empty());
    EXPECT_TRUE(test::eventually([&] { return server_->stats().broadcasts == 1; }));
    EXPECT_EQ(units.model_at(0).holding_registers().get(7), 0xBEEF);
    auto s = server_->stats();
    EXPECT_EQ(s.exceptions, 1u);
    EXPECT_EQ(s.fault_delayed, 1u);
}

TEST_F(SerialServerTest, NoAnswerAndDropFaultsLeaveTheRequestUnanswered) {
    slave::FaultConfig silent;
    silent.no_answer_rate = 1.0;
    start(codec::Framing::Rtu, silent);
    send(rtu(1, {0x03, 0x00, 0x05, 0x00, 0x01}));
    EXPECT_TRUE(read_for(pty.master, 1, 300).empty());
    EXPECT_EQ(server_->stats().fault_silent, 1u);
    EXPECT_EQ(server_->stats().responses, 0u);
}

TEST_F(SerialServerTest, AsciiRequestGetsAnAsciiAnswer) {
    start(codec::Framing::Ascii);
    const std::vector<std::uint8_t> pdu{0x03, 0x00, 0x05, 0x00, 0x01};
    std::string text(codec::ascii_frame_size(pdu.size()), '\0');
    codec::encode_ascii_frame(
        1, pdu, codec::MutableBytes(reinterpret_cast<std::uint8_t*>(text.data()), text.size()));
    send(std::vector<std::uint8_t>(text.begin(), text.end()));
    auto got = read_for(pty.master, 15, 5000);
    EXPECT_EQ(std::string(got.begin(), got.end()), ":0103021234B4\r\n");
}

}  // namespace
