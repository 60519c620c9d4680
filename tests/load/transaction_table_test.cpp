#include "load/transaction_table.hpp"

#include <gtest/gtest.h>

#include <deque>
#include <vector>

#include "load/rng.hpp"

namespace mbstorm::load {
namespace {

TEST(TransactionTable, CapacityIsAtLeastTwiceTheDepth) {
    TransactionTable table(16);
    EXPECT_EQ(table.capacity(), 32u);
    for (std::uint32_t i = 0; i < table.capacity(); ++i) ASSERT_NE(table.begin(0, 0), nullptr);
    EXPECT_EQ(table.begin(0, 0), nullptr);
    EXPECT_EQ(table.outstanding(), 32u);
}

TEST(TransactionTable, IdsWrapPast65535AndStillMatch) {
    TransactionTable table(4, 65530);
    std::vector<std::uint16_t> ids;
    for (int i = 0; i < 12; ++i) {
        Transaction* t = table.begin(i, i);
        ASSERT_NE(t, nullptr);
        t->request.address = static_cast<std::uint16_t>(1000 + i);
        ids.push_back(t->transaction_id());
        Transaction* matched = nullptr;
        ASSERT_EQ(table.complete(t->transaction_id(), matched), MatchResult::Matched);
        EXPECT_EQ(matched->request.address, 1000 + i);
    }
    EXPECT_EQ(ids, (std::vector<std::uint16_t>{65530, 65531, 65532, 65533, 65534, 65535, 0, 1, 2, 3,
                                               4, 5}));
    EXPECT_EQ(table.outstanding(), 0u);
}

TEST(TransactionTable, UnknownDuplicateAndLateAreTold) {
    TransactionTable table(4);
    Transaction* matched = nullptr;
    EXPECT_EQ(table.complete(0, matched), MatchResult::Unknown);  // nothing sent yet
    Transaction* a = table.begin(0, 0);
    Transaction* b = table.begin(0, 0);
    const std::uint16_t a_id = a->transaction_id(), b_id = b->transaction_id();
    EXPECT_EQ(table.complete(a_id, matched), MatchResult::Matched);
    EXPECT_EQ(table.complete(a_id, matched), MatchResult::Duplicate);
    EXPECT_EQ(table.complete(777, matched), MatchResult::Unknown);
    EXPECT_EQ(table.expire(100, [](const Transaction&) {}), 1u);
    EXPECT_EQ(table.complete(b_id, matched), MatchResult::Late);
    EXPECT_EQ(table.outstanding(), 0u);
}

TEST(TransactionTable, TimeoutsExpireOldestFirstAndStopAtTheFirstInTime) {
    TransactionTable table(8);
    for (std::int64_t sent : {100, 200, 300, 400}) table.begin(sent, sent);
    Transaction* matched = nullptr;
    ASSERT_EQ(table.complete(1, matched), MatchResult::Matched);  // the 200 one answered
    std::vector<std::int64_t> expired;
    EXPECT_EQ(table.expire(300, [&](const Transaction& t) { expired.push_back(t.sent_ns); }), 2u);
    EXPECT_EQ(expired, (std::vector<std::int64_t>{100, 300}));
    EXPECT_EQ(table.outstanding(), 1u);
    EXPECT_EQ(table.oldest_sent_ns(), 400);
    EXPECT_EQ(table.expire(399, [](const Transaction&) {}), 0u);
}

TEST(TransactionTable, ASlowTransactionKeepsItsIdWhileOthersWrapAround) {
    TransactionTable table(2);  // capacity 8
    Transaction* slow = table.begin(0, 0);
    slow->request.address = 4242;
    const std::uint16_t slow_id = slow->transaction_id();
    Transaction* matched = nullptr;
    for (int i = 0; i < 70000; ++i) {  // more than the whole id space
        Transaction* t = table.begin(1, 1);
        ASSERT_NE(t, nullptr);
        ASSERT_NE(t->transaction_id(), slow_id);
        t->request.address = 1;
        ASSERT_EQ(table.complete(t->transaction_id(), matched), MatchResult::Matched);
    }
    ASSERT_EQ(table.complete(slow_id, matched), MatchResult::Matched);
    EXPECT_EQ(matched->request.address, 4242);
}

TEST(TransactionTable, OutOfOrderAnswersOverManyWrapsMatchTheirOwnRequest) {
    constexpr std::uint32_t kDepth = 16;
    TransactionTable table(kDepth);
    Rng rng(5);
    std::deque<std::pair<std::uint16_t, std::uint16_t>> window;  // id, payload tag
    std::uint16_t tag = 0;
    for (int i = 0; i < 200000; ++i) {
        while (window.size() < kDepth) {
            Transaction* t = table.begin(i, i);
            ASSERT_NE(t, nullptr);
            t->request.address = ++tag;
            window.emplace_back(t->transaction_id(), tag);
        }
        const std::size_t pick = rng.below(static_cast<std::uint32_t>(window.size()));
        Transaction* matched = nullptr;
        ASSERT_EQ(table.complete(window[pick].first, matched), MatchResult::Matched);
        ASSERT_EQ(matched->request.address, window[pick].second);
        window.erase(window.begin() + static_cast<std::ptrdiff_t>(pick));
    }
    EXPECT_EQ(table.outstanding(), kDepth - 1);
}

TEST(TransactionTable, AbortAllEndsEveryOutstandingTransaction) {
    TransactionTable table(4);
    for (int i = 0; i < 5; ++i) table.begin(i, i);
    Transaction* matched = nullptr;
    table.complete(2, matched);
    int aborted = 0;
    EXPECT_EQ(table.abort_all([&](const Transaction&) { ++aborted; }), 4u);
    EXPECT_EQ(aborted, 4);
    EXPECT_EQ(table.outstanding(), 0u);
    EXPECT_EQ(table.complete(0, matched), MatchResult::Late);
}

TEST(TransactionTable, CancelGivesTheSlotBack) {
    TransactionTable table(1);
    Transaction* t = table.begin(0, 0);
    table.cancel(t);
    EXPECT_EQ(table.outstanding(), 0u);
    Transaction* matched = nullptr;
    EXPECT_EQ(table.complete(0, matched), MatchResult::Unknown);
}

}  // namespace
}  // namespace mbstorm::load
