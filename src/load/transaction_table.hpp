// The outstanding transactions of one connection, matched by MBAP transaction id.
//
// Ids count up and wrap past 65535. A slot array of power-of-two size (>= 2 * depth, dividing
// 65536) is indexed by id & mask, so lookup is O(1) and wrap-around needs no special case. If
// the slot of the next id is still held by an old slow transaction, that id is skipped: two
// outstanding transactions never share an id. Every slot also remembers how its last
// transaction ended, which tells a duplicate (already answered) or late (already timed out)
// response from one with an id nobody used. 64-bit sequence numbers order the slots for the
// timeout sweep, which walks from the oldest and stops at the first one still in time.
#pragma once

#include <climits>
#include <cstdint>
#include <memory>

#include "load/request_info.hpp"

namespace mbstorm::load {

struct Transaction {
    std::uint64_t sequence = 0;    // transaction id = low 16 bits
    std::int64_t sent_ns = 0;      // when the request was queued for sending
    std::int64_t intended_ns = 0;  // open loop: when the schedule wanted it sent (else sent_ns)
    RequestInfo request;
    enum class State : std::uint8_t { Free, Outstanding, Answered, TimedOut, Aborted };
    State state = State::Free;

    std::uint16_t transaction_id() const noexcept { return static_cast<std::uint16_t>(sequence); }
};

enum class MatchResult : std::uint8_t {
    Matched,    // an outstanding transaction: the returned pointer is it
    Unknown,    // no transaction with this id was sent recently
    Duplicate,  // this id was already answered
    Late,       // this id already timed out (or its connection was reset)
};

class TransactionTable {
  public:
    explicit TransactionTable(std::uint32_t depth, std::uint16_t first_id = 0);

    std::uint32_t capacity() const noexcept { return mask_ + 1; }
    std::uint32_t outstanding() const noexcept { return outstanding_; }
    // Id the next begin() will try first.
    std::uint16_t next_id() const noexcept { return static_cast<std::uint16_t>(next_sequence_); }

    // Starts a transaction; nullptr when capacity() are outstanding. The caller fills
    // `request` and encodes with transaction_id(). Inline, like complete(): both run once per
    // request on the engine's hot path.
    Transaction* begin(std::int64_t sent_ns, std::int64_t intended_ns) noexcept {
        if (outstanding_ > mask_) return nullptr;
        for (;;) {
            Transaction& t = slots_[next_sequence_ & mask_];
            const std::uint64_t sequence = next_sequence_++;
            if (t.state == Transaction::State::Outstanding) continue;  // held by a slow one: skip
            t.sequence = sequence;
            t.sent_ns = sent_ns;
            t.intended_ns = intended_ns;
            t.state = Transaction::State::Outstanding;
            ++outstanding_;
            return &t;
        }
    }

    // Matches a response id. On Matched the transaction is marked answered; `out` stays valid
    // until the next begin().
    MatchResult complete(std::uint16_t transaction_id, Transaction*& out) noexcept {
        Transaction& t = slots_[transaction_id & mask_];
        if (t.sequence == UINT64_MAX || t.transaction_id() != transaction_id) {
            return MatchResult::Unknown;
        }
        switch (t.state) {
            case Transaction::State::Outstanding:
                t.state = Transaction::State::Answered;
                --outstanding_;
                out = &t;
                return MatchResult::Matched;
            case Transaction::State::Answered:
                return MatchResult::Duplicate;
            case Transaction::State::TimedOut:
            case Transaction::State::Aborted:
                return MatchResult::Late;
            case Transaction::State::Free:
                break;
        }
        return MatchResult::Unknown;
    }

    // Sends back the transaction just begun (e.g. the encoder failed): the id is reusable.
    void cancel(Transaction* t) noexcept;

    // Times out every transaction sent at or before `deadline_sent_ns`, oldest first; calls
    // on_timeout(const Transaction&) for each. Returns how many.
    template <class Fn>
    std::uint32_t expire(std::int64_t deadline_sent_ns, Fn&& on_timeout) noexcept {
        std::uint32_t expired = 0;
        while (oldest_sequence_ < next_sequence_) {
            Transaction& t = slots_[oldest_sequence_ & mask_];
            if (t.sequence == oldest_sequence_ && t.state == Transaction::State::Outstanding) {
                if (t.sent_ns > deadline_sent_ns) break;
                t.state = Transaction::State::TimedOut;
                --outstanding_;
                ++expired;
                on_timeout(static_cast<const Transaction&>(t));
            }
            ++oldest_sequence_;
        }
        return expired;
    }

    // The oldest outstanding transaction's send time (for scheduling the next sweep), or
    // INT64_MAX when none is outstanding.
    std::int64_t oldest_sent_ns() noexcept;

    // Ends every outstanding transaction (connection lost); calls fn(const Transaction&).
    template <class Fn>
    std::uint32_t abort_all(Fn&& fn) noexcept {
        std::uint32_t aborted = 0;
        for (; oldest_sequence_ < next_sequence_ && outstanding_ > 0; ++oldest_sequence_) {
            Transaction& t = slots_[oldest_sequence_ & mask_];
            if (t.sequence == oldest_sequence_ && t.state == Transaction::State::Outstanding) {
                t.state = Transaction::State::Aborted;
                --outstanding_;
                ++aborted;
                fn(static_cast<const Transaction&>(t));
            }
        }
        oldest_sequence_ = next_sequence_;
        return aborted;
    }

  private:
    std::unique_ptr<Transaction[]> slots_;
    std::uint32_t mask_ = 0;
    std::uint32_t outstanding_ = 0;
    std::uint64_t next_sequence_ = 0;
    std::uint64_t oldest_sequence_ = 0;  // nothing older than this is outstanding
};

}  // namespace mbstorm::load
