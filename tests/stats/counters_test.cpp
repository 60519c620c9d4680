#include "stats/counters.hpp"

#include <gtest/gtest.h>

#include <set>
#include <string>

namespace mbstorm::stats {
namespace {

TEST(OutcomeCounters, CountsOutcomesAndExceptionCodes) {
    OutcomeCounters c;
    c.record(Outcome::Ok);
    c.record(Outcome::Ok);
    c.record(Outcome::Timeout);
    c.record_exception(0x02);
    c.record_exception(0x02);
    c.record_exception(0x0B);
    EXPECT_EQ(c.ok(), 2u);
    EXPECT_EQ(c.count(Outcome::Exception), 3u);
    EXPECT_EQ(c.exceptions[0x02], 2u);
    EXPECT_EQ(c.exceptions[0x0B], 1u);
    EXPECT_EQ(c.completed(), 6u);
    EXPECT_EQ(c.errors(), 4u);
}

TEST(OutcomeCounters, StrayResponsesAreCountedButAreNotTransactions) {
    OutcomeCounters c;
    c.record(Outcome::Ok);
    c.record(Outcome::Timeout);
    c.record(Outcome::UnknownId);
    c.record(Outcome::DuplicateId);
    c.record(Outcome::DuplicateId);
    EXPECT_EQ(c.completed(), 2u);
    EXPECT_EQ(c.errors(), 1u);
    EXPECT_EQ(c.stray_responses(), 3u);
    EXPECT_EQ(c.count(Outcome::DuplicateId), 2u);
}

TEST(OutcomeCounters, MergeAddsEveryField) {
    OutcomeCounters a, b;
    a.record(Outcome::WrongUnitId);
    a.bytes_sent = 10;
    b.record(Outcome::WrongUnitId);
    b.record_exception(0x04);
    b.transactions_sent = 3;
    b.bytes_received = 7;
    a.add(b);
    EXPECT_EQ(a.count(Outcome::WrongUnitId), 2u);
    EXPECT_EQ(a.exceptions[0x04], 1u);
    EXPECT_EQ(a.transactions_sent, 3u);
    EXPECT_EQ(a.bytes_sent, 10u);
    EXPECT_EQ(a.bytes_received, 7u);
    a.reset();
    EXPECT_EQ(a.completed(), 0u);
}

TEST(OutcomeCounters, EveryOutcomeHasAUniqueName) {
    std::set<std::string> names;
    for (std::size_t i = 0; i < kOutcomeCount; ++i) {
        const auto name = outcome_name(static_cast<Outcome>(i));
        EXPECT_NE(name, "unknown");
        names.emplace(name);
    }
    EXPECT_EQ(names.size(), kOutcomeCount);
    EXPECT_EQ(outcome_name(Outcome::ValueMismatch), "value_mismatch");
    EXPECT_EQ(outcome_name(Outcome::FramingError), "framing_error");
    EXPECT_EQ(outcome_name(Outcome::CrcError), "crc_error");
    EXPECT_EQ(outcome_name(static_cast<Outcome>(200)), "unknown");
}

}  // namespace
}  // namespace mbstorm::stats
