// SerialRunner (run --serial) on a pseudo-terminal: the test plays the slave on the pty's
// master side, answering each request as the case needs (a good frame, a bad CRC, another
// unit, an exception, nothing, a delay, a hang-up), and checks what the runner counted
// against what went over the line. Counts and outcomes only: no assertion on how fast.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <pty.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <functional>
#include <thread>
#include <vector>

#include "codec/rtu.hpp"
#include "load/serial_load.hpp"
#include "net/clock.hpp"

using namespace mbstorm;
using load::SerialRunner;
using stats::Outcome;

namespace {

using Frame = std::vector<std::uint8_t>;

Frame rtu(std::uint8_t unit, const Frame& pdu) {
    Frame out(pdu.size() + 3);
    out.resize(codec::encode_rtu_frame(unit, pdu, out).size);
    return out;
}

// The normal answer to a read request (FC01-04, unit and PDU from `request`): zeros.
Frame read_answer(const Frame& request) {
    const std::uint8_t fc = request[1];
    const unsigned quantity = (request[4] << 8) | request[5];
    const unsigned bytes = fc <= 2 ? (quantity + 7) / 8 : quantity * 2;
    Frame pdu{fc, static_cast<std::uint8_t>(bytes)};
    pdu.resize(2 + bytes);
    return rtu(request[0], pdu);
}

// What the slave does with request number `index` (0-based): the bytes to answer (empty:
// silence) and how long to wait first. `hang_up` closes the line instead.
struct Reply {
    Frame bytes;
    std::chrono::milliseconds delay{0};
    bool hang_up = false;
};
using Policy = std::function<Reply(std::size_t index, const Frame& request)>;

class SerialLoadTest : public ::testing::Test {
  protected:
    void SetUp() override {
        int slave = -1;
        char name[128] = {};
        ASSERT_EQ(::openpty(&pty_, &slave, name, nullptr, nullptr), 0);
        ::close(slave);
        plan_.serial.device = name;
        plan_.serial.line.parity = net::Parity::None;
        plan_.operations.push_back(load::Operation{});  // FC03 unit 1, 1 register at 0
        plan_.transaction_timeout = std::chrono::seconds(2);
    }
    void TearDown() override {
        done_ = true;
        if (slave_.joinable()) slave_.join();
        if (pty_ >= 0) ::close(pty_);
    }

    // Plays the slave with `policy` until the test ends or it hangs up.
    void serve(Policy policy) {
        slave_ = std::thread([this, policy] {
            Frame pending;
            std::uint8_t buf[512];
            while (!done_) {
                pollfd p{pty_, POLLIN, 0};
                if (::poll(&p, 1, 20) <= 0) continue;
                const ssize_t n = ::read(pty_, buf, sizeof buf);
                if (n <= 0) continue;
                pending.insert(pending.end(), buf, buf + n);
                const codec::RtuLength len = codec::rtu_request_length(pending);
                if (len.status != codec::RtuLength::Status::Known || pending.size() < len.size)
                    continue;
                const Frame request(pending.begin(), pending.begin() + len.size);
                pending.erase(pending.begin(), pending.begin() + len.size);
                requests_.push_back(request);
                arrivals_.push_back(net::now_ns());
                bytes_in_ += request.size();
                const Reply r = policy(requests_.size() - 1, request);
                if (r.hang_up) {
                    ::close(pty_);
                    pty_ = -1;
                    return;
                }
                std::this_thread::sleep_for(r.delay);
                if (r.bytes.empty()) continue;
                bytes_out_ += r.bytes.size();
                (void)!::write(pty_, r.bytes.data(), r.bytes.size());
            }
        });
    }

    // Runs the plan to its end (bounded: 60 s, or `length_ns`) and returns the runner for its
    // counts. start_ns_: when it began measuring.
    std::unique_ptr<SerialRunner> run(std::int64_t length_ns = 60 * net::kNsPerSec) {
        schedule_ = std::make_unique<load::StageSchedule>(plan_);
        start_ns_ = net::now_ns();
        auto runner = std::make_unique<SerialRunner>(
            load::SerialRunSetup{&plan_, &options_, schedule_.get(), &timeline_, nullptr, start_ns_,
                                 start_ns_, start_ns_ + length_ns, nullptr});
        EXPECT_EQ(runner->open(), Error::none());
        runner->run();
        EXPECT_EQ(runner->open_connections(), 0u);
        done_ = true;
        if (slave_.joinable()) slave_.join();
        return runner;
    }

    int pty_ = -1;
    load::Plan plan_;
    load::EngineOptions options_;
    std::unique_ptr<load::StageSchedule> schedule_;
    stats::IntervalTimeline timeline_{net::kNsPerSec, 1, 128};
    std::thread slave_;
    std::atomic<bool> done_{false};
    std::vector<Frame> requests_;
    std::vector<std::int64_t> arrivals_;  // when each request was read
    std::int64_t start_ns_ = 0;
    std::uint64_t bytes_in_ = 0;
    std::uint64_t bytes_out_ = 0;
};

Reply answer_reads(std::size_t, const Frame& request) {
    return {read_answer(request)};
}

std::uint64_t latency_samples(const SerialRunner& r) {
    std::uint64_t n = 0;
    for (const auto& op : r.operations) n += op.latency.total_count();
    return n;
}

TEST_F(SerialLoadTest, ClosedLoopSendsTheCountAndAccountsEveryByte) {
    load::Operation input;
    input.function = codec::to_byte(codec::FunctionCode::ReadInputRegisters);
    input.quantity = 3;
    input.weight = 2;
    plan_.operations.push_back(input);
    plan_.transactions = 30;
    serve(answer_reads);
    const auto r = run();
    EXPECT_EQ(r->fatal_error, Error::none());
    ASSERT_EQ(requests_.size(), 30u);
    EXPECT_EQ(r->counters.transactions_sent, 30u);
    EXPECT_EQ(r->counters.ok(), 30u);
    EXPECT_EQ(r->counters.completed(), 30u);
    // Bytes as on the wire (unit, PDU, CRC), both ways.
    EXPECT_EQ(r->counters.bytes_sent, bytes_in_);
    EXPECT_EQ(r->counters.bytes_received, bytes_out_);
    // Each operation's row counts the requests of its function the slave saw.
    ASSERT_EQ(r->operations.size(), 2u);
    std::uint64_t fc03 = 0;
    for (const Frame& q : requests_) fc03 += q[1] == 0x03 ? 1 : 0;
    EXPECT_GT(fc03, 0u);
    EXPECT_LT(fc03, 30u);
    EXPECT_EQ(r->operations[0].counters.transactions_sent, fc03);
    EXPECT_EQ(r->operations[1].counters.transactions_sent, 30u - fc03);
    EXPECT_EQ(r->operations[0].counters.ok() + r->operations[1].counters.ok(), 30u);
    EXPECT_EQ(latency_samples(*r), 30u);
    EXPECT_EQ(r->bad_checks, 0u);
}

TEST_F(SerialLoadTest, BadCrcIsCountedAsACrcErrorAndNotTimed) {
    plan_.transactions = 10;
    serve([](std::size_t i, const Frame& request) {
        Reply r{read_answer(request)};
        if (i % 2 == 1) r.bytes.back() ^= 0x5A;  // every second answer's CRC is wrong
        return r;
    });
    const auto r = run();
    EXPECT_EQ(r->counters.transactions_sent, 10u);
    EXPECT_EQ(r->counters.count(Outcome::CrcError), 5u);
    EXPECT_EQ(r->bad_checks, 5u);
    EXPECT_EQ(r->counters.ok(), 5u);
    EXPECT_EQ(r->operations[0].counters.count(Outcome::CrcError), 5u);
    EXPECT_EQ(latency_samples(*r), 5u);  // a broken answer has no latency
}

TEST_F(SerialLoadTest, EachWayALineFailsIsItsOwnOutcome) {
    plan_.transactions = 6;
    plan_.transaction_timeout = std::chrono::milliseconds(300);
    serve([](std::size_t i, const Frame& request) -> Reply {
        switch (i) {
            case 1:
                return {};  // silence: a timeout, and the line goes on
            case 3:
                return {rtu(2, {0x03, 0x02, 0x00, 0x00})};  // another unit answers
            case 4:
                return {rtu(1, {0x83, 0x02})};  // exception 02
            default:
                return {read_answer(request)};
        }
    });
    const auto r = run();
    EXPECT_EQ(requests_.size(), 6u);
    EXPECT_EQ(r->counters.transactions_sent, 6u);
    EXPECT_EQ(r->counters.ok(), 3u);
    EXPECT_EQ(r->counters.count(Outcome::Timeout), 1u);
    EXPECT_EQ(r->counters.count(Outcome::WrongUnitId), 1u);
    EXPECT_EQ(r->counters.count(Outcome::Exception), 1u);
    EXPECT_EQ(r->counters.exceptions[2], 1u);
    EXPECT_EQ(r->counters.completed(), 6u);
    EXPECT_EQ(latency_samples(*r), 4u);  // the answers and the exception are timed
    EXPECT_EQ(r->bad_checks, 0u);
}

TEST_F(SerialLoadTest, VerifierRejectionIsAValueMismatch) {
    plan_.transactions = 4;
    options_.verifier.check = [](void*, const load::RequestInfo&, const codec::Response&) {
        return false;
    };
    serve(answer_reads);
    const auto r = run();
    EXPECT_EQ(r->counters.transactions_sent, 4u);
    EXPECT_EQ(r->counters.count(Outcome::ValueMismatch), 4u);
    EXPECT_EQ(r->counters.ok(), 0u);
}

TEST_F(SerialLoadTest, OpenLoopTimesFromTheIntendedSendAndCountsLateSends) {
    // 1000/s asked, every answer held 5 ms: each send after the first is late, and the
    // latency (from the intended send) includes the wait the service time leaves out.
    plan_.model = load::LoadModel::OpenLoop;
    plan_.rate = 1000;
    plan_.transactions = 8;
    serve([](std::size_t, const Frame& request) {
        return Reply{read_answer(request), std::chrono::milliseconds(5)};
    });
    const auto r = run();
    EXPECT_EQ(r->counters.transactions_sent, 8u);
    EXPECT_EQ(r->counters.ok(), 8u);
    EXPECT_EQ(r->service_time.total_count(), 8u);
    EXPECT_EQ(latency_samples(*r), 8u);
    EXPECT_GE(r->target_lag.late_sends, 7u);
    EXPECT_GE(r->target_lag.max_lag_ns, 4'000'000u);  // the 5 ms hold, less one 1 ms period
    EXPECT_GT(r->operations[0].latency.max(), r->service_time.max());
}

TEST_F(SerialLoadTest, ClosedLoopDoesNotCountLateSends) {
    plan_.transactions = 4;
    serve([](std::size_t, const Frame& request) {
        return Reply{read_answer(request), std::chrono::milliseconds(5)};
    });
    const auto r = run();
    EXPECT_EQ(r->counters.ok(), 4u);
    EXPECT_EQ(r->target_lag.late_sends, 0u);
    EXPECT_EQ(r->service_time.total_count(), 0u);  // service time is the open loop's
}

TEST_F(SerialLoadTest, AStageWithoutAConnectionKeepsTheMasterOffTheLine) {
    plan_.transactions = 0;
    plan_.stages = {{std::chrono::milliseconds(300), {}, 0u, load::Ramp::Constant, "off"},
                    {std::chrono::seconds(1), {}, 1u, load::Ramp::Constant, "on"}};
    serve(answer_reads);
    const auto r = run(1300 * net::kNsPerMs);
    ASSERT_FALSE(requests_.empty());
    for (const std::int64_t at : arrivals_) EXPECT_GE(at - start_ns_, 300 * net::kNsPerMs);
    ASSERT_EQ(r->stages.size(), 2u);
    EXPECT_EQ(r->stages[0].counters.transactions_sent, 0u);
    EXPECT_EQ(r->stages[1].counters.transactions_sent, requests_.size());
    EXPECT_EQ(r->counters.transactions_sent, requests_.size());
    EXPECT_EQ(r->counters.ok(), requests_.size());
}

TEST_F(SerialLoadTest, StopEndsTheRunAfterTheTransactionOnTheLine) {
    std::atomic<bool> stop{false};
    options_.stop = &stop;
    plan_.transactions = 0;  // no count: only the stop (or the 60 s bound) ends it
    serve([&stop](std::size_t i, const Frame& request) {
        if (i == 2) stop = true;  // before the third answer goes out
        return Reply{read_answer(request)};
    });
    const auto r = run();
    EXPECT_EQ(r->fatal_error, Error::none());
    EXPECT_LT(r->finished_ns, start_ns_ + 60 * net::kNsPerSec);  // not the run's end
    EXPECT_EQ(requests_.size(), 3u);
    EXPECT_EQ(r->counters.transactions_sent, 3u);
    EXPECT_EQ(r->counters.ok(), 3u);
}

TEST_F(SerialLoadTest, ALineThatGoesAwayEndsTheRunWithItsError) {
    plan_.transactions = 0;
    plan_.transaction_timeout = std::chrono::milliseconds(200);
    serve([](std::size_t i, const Frame& request) {
        Reply r{read_answer(request)};
        r.hang_up = i == 2;  // the third request is never answered: the line is gone
        return r;
    });
    const auto r = run();
    EXPECT_NE(r->fatal_error.text().find(plan_.serial.device), std::string::npos) << r->fatal_error;
    EXPECT_LT(r->finished_ns, start_ns_ + 60 * net::kNsPerSec);  // not the run's end
    EXPECT_EQ(r->counters.ok(), 2u);
    EXPECT_EQ(r->counters.count(Outcome::Timeout), 1u);
    EXPECT_EQ(r->counters.transactions_sent, 3u);  // the send that failed went nowhere
}

}  // namespace
