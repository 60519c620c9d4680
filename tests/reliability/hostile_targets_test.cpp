// The load engine against hostile targets: whatever the target does, every transaction sent is
// accounted for exactly once, and each misbehaviour lands in its own class.
#include <gtest/gtest.h>

#include <chrono>
#include <memory>
#include <thread>

#include "hostile_target.hpp"
#include "load/engine.hpp"

namespace mbstorm::load {
namespace {

using namespace std::chrono_literals;
using stats::Outcome;
using test::HostileTarget;

Plan plan_for(std::uint16_t port) {
    Plan plan;
    plan.host = "127.0.0.1";
    plan.port = port;
    Operation op;
    op.name = "read";
    op.function = 0x03;
    op.first_address = 0;
    op.last_address = 99;
    op.quantity = 2;
    plan.operations = {op};
    plan.threads = 1;
    plan.connections = 2;
    plan.depth = 4;
    plan.duration = 800ms;
    plan.transaction_timeout = 200ms;
    plan.reconnect_backoff_min = 5ms;
    plan.reconnect_backoff_max = 50ms;
    return plan;
}

void expect_accounted(const LoadResult& r) {
    EXPECT_EQ(r.run.counters.transactions_sent, r.run.counters.completed() + r.pending_at_end);
}

bool has_note(const LoadResult& r, const std::string& part) {
    for (const auto& n : r.run.metadata.notes)
        if (n.find(part) != std::string::npos) return true;
    return false;
}

// Before: a stream that lost MBAP framing ended its transactions as connection_closed.
TEST(HostileTargets, GarbageAnswersAreFramingErrorsNotClosedConnections) {
    for (auto mode : {HostileTarget::Mode::Garbage, HostileTarget::Mode::LengthFFFF}) {
        HostileTarget target(mode);
        ASSERT_TRUE(target.ok());
        const LoadResult r = run_load(plan_for(target.port()));
        ASSERT_TRUE(r.ok()) << r.error;
        const auto& c = r.run.counters;
        EXPECT_GT(c.count(Outcome::FramingError), 0u);
        EXPECT_EQ(c.count(Outcome::ConnectionClosed), 0u);
        EXPECT_EQ(c.count(Outcome::Malformed), 0u);
        EXPECT_EQ(c.ok(), 0u);
        EXPECT_EQ(r.run.connections.closed_by_peer, 0u);
        EXPECT_GT(r.framing_errors, 0u);
        expect_accounted(r);
    }
}

TEST(HostileTargets, SilentTargetTimesOutEveryTransaction) {
    HostileTarget target(HostileTarget::Mode::Silent);
    const LoadResult r = run_load(plan_for(target.port()));
    ASSERT_TRUE(r.ok()) << r.error;
    EXPECT_GT(r.run.counters.count(Outcome::Timeout), 0u);
    EXPECT_EQ(r.run.counters.ok(), 0u);
    expect_accounted(r);
}

TEST(HostileTargets, WrongIdsAreStrayAndTheirTransactionsTimeOut) {
    HostileTarget target(HostileTarget::Mode::WrongId);
    const LoadResult r = run_load(plan_for(target.port()));
    ASSERT_TRUE(r.ok()) << r.error;
    EXPECT_GT(r.run.counters.count(Outcome::UnknownId), 0u);
    EXPECT_GT(r.run.counters.count(Outcome::Timeout), 0u);
    EXPECT_EQ(r.run.counters.ok(), 0u);
    expect_accounted(r);
}

TEST(HostileTargets, DuplicatesAreCountedApartFromTransactions) {
    HostileTarget target(HostileTarget::Mode::Duplicate);
    const LoadResult r = run_load(plan_for(target.port()));
    ASSERT_TRUE(r.ok()) << r.error;
    EXPECT_GT(r.run.counters.ok(), 0u);
    EXPECT_GT(r.run.counters.count(Outcome::DuplicateId), 0u);
    EXPECT_EQ(r.run.counters.errors(), 0u);
    expect_accounted(r);
}

TEST(HostileTargets, CloseAfterEachAnswerReconnectsAndAccountsEverything) {
    HostileTarget target(HostileTarget::Mode::CloseAfterAnswer);
    const LoadResult r = run_load(plan_for(target.port()));
    ASSERT_TRUE(r.ok()) << r.error;
    EXPECT_GT(r.run.counters.ok(), 0u);
    EXPECT_GT(r.run.connections.reconnects, 0u);
    EXPECT_GT(r.run.connections.closed_by_peer, 0u);
    expect_accounted(r);
}

// Before: the run went on to its end with nothing said; the throughput was averaged over the
// whole run and the reports had no note.
TEST(HostileTargets, TargetKilledMidRunIsANoteAndLostAtTheEnd) {
    auto target = std::make_unique<HostileTarget>(HostileTarget::Mode::Honest);
    Plan plan = plan_for(target->port());
    plan.duration = 1500ms;
    std::thread killer([&] {
        std::this_thread::sleep_for(400ms);
        target->kill();
    });
    const LoadResult r = run_load(plan);
    killer.join();
    ASSERT_TRUE(r.ok()) << r.error;
    EXPECT_GT(r.run.counters.ok(), 0u);
    EXPECT_TRUE(r.target_lost_at_end);
    EXPECT_TRUE(has_note(r, "target lost at")) << testing::PrintToString(r.run.metadata.notes);
    EXPECT_TRUE(has_note(r, "not back by the end"));
    expect_accounted(r);
}

TEST(HostileTargets, TargetThatComesBackIsANoteWithBothTimes) {
    auto target = std::make_unique<HostileTarget>(HostileTarget::Mode::Honest);
    const std::uint16_t port = target->port();
    Plan plan = plan_for(port);
    plan.duration = 2500ms;
    std::thread killer([&] {
        std::this_thread::sleep_for(400ms);
        target->kill();
        std::this_thread::sleep_for(900ms);
        target = std::make_unique<HostileTarget>(HostileTarget::Mode::Honest, port);
    });
    const LoadResult r = run_load(plan);
    killer.join();
    ASSERT_TRUE(target->ok()) << "the port was taken meanwhile";
    ASSERT_TRUE(r.ok()) << r.error;
    EXPECT_FALSE(r.target_lost_at_end);
    EXPECT_TRUE(has_note(r, ", back at")) << testing::PrintToString(r.run.metadata.notes);
    EXPECT_GT(r.run.connections.reconnects, 0u);
    expect_accounted(r);
}

// A stage that closes every connection on purpose is not a lost target.
TEST(HostileTargets, AStageWithNoConnectionsIsNoOutage) {
    HostileTarget target(HostileTarget::Mode::Honest);
    Plan plan = plan_for(target.port());
    Stage up, none, again;
    up.duration = 300ms;
    none.duration = 900ms;
    none.target_connections = 0;
    again.duration = 300ms;
    again.target_connections = 2;
    plan.stages = {up, none, again};
    const LoadResult r = run_load(plan);
    ASSERT_TRUE(r.ok()) << r.error;
    EXPECT_GT(r.run.counters.ok(), 0u);
    EXPECT_FALSE(has_note(r, "target lost")) << testing::PrintToString(r.run.metadata.notes);
    EXPECT_FALSE(r.target_lost_at_end);
    expect_accounted(r);
}

// Before: a run shorter than the connect timeout against a silent address ended as "0
// transactions", ok.
TEST(HostileTargets, NoConnectionDuringAShortRunIsAnError) {
    test::HangingListener silent;  // connects hang, like 192.0.2.99
    Plan plan = plan_for(silent.port());
    plan.duration = 300ms;
    plan.connect_timeout = 3s;
    const auto t0 = std::chrono::steady_clock::now();
    const LoadResult r = run_load(plan);
    EXPECT_FALSE(r.ok());
    EXPECT_NE(
        r.error.message().find("cannot connect to 127.0.0.1:" + std::to_string(silent.port())),
        std::string::npos)
        << r.error;
    EXPECT_NE(r.error.message().find("no connection was established"), std::string::npos)
        << r.error;
    EXPECT_LT(std::chrono::steady_clock::now() - t0, 3s);
}

}  // namespace
}  // namespace mbstorm::load
