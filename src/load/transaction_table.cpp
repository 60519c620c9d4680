#include "load/transaction_table.hpp"

#include <algorithm>
#include <bit>
#include <climits>

namespace mbstorm::load {

TransactionTable::TransactionTable(std::uint32_t depth, std::uint16_t first_id) {
    // Twice the depth leaves room for skipped ids; at most 65536 so that the slot index of an
    // id does not change when the id wraps.
    const std::uint32_t wanted = std::clamp<std::uint32_t>(depth, 1, 32768) * 2;
    const std::uint32_t size = std::max<std::uint32_t>(std::bit_ceil(wanted), 8);
    slots_ = std::make_unique<Transaction[]>(size);
    mask_ = size - 1;
    next_sequence_ = oldest_sequence_ = first_id;
    // Mark every slot as never used so that no id looks answered before it was sent.
    for (std::uint32_t i = 0; i < size; ++i) slots_[i].sequence = UINT64_MAX;
}

void TransactionTable::cancel(Transaction* t) noexcept {
    if (t == nullptr || t->state != Transaction::State::Outstanding) return;
    t->state = Transaction::State::Free;
    t->sequence = UINT64_MAX;
    --outstanding_;
}

std::int64_t TransactionTable::oldest_sent_ns() noexcept {
    while (oldest_sequence_ < next_sequence_) {
        const Transaction& t = slots_[oldest_sequence_ & mask_];
        if (t.sequence == oldest_sequence_ && t.state == Transaction::State::Outstanding) {
            return t.sent_ns;
        }
        ++oldest_sequence_;
    }
    return INT64_MAX;
}

}  // namespace mbstorm::load
