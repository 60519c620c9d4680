#include "server/out_queue.hpp"

#include <algorithm>

namespace mbstorm::server {

BlockPool::~BlockPool() {
    for (OutBlock* b : all_) delete b;
}

OutBlock* BlockPool::get() {
    if (free_) {
        OutBlock* b = free_;
        free_ = b->next;
        b->next = nullptr;
        b->begin = b->end = 0;
        --free_count_;
        unused_since_trim_ = std::min(unused_since_trim_, free_count_);
        return b;
    }
    // Room first (doubling), so that a failed allocation cannot leave a block unowned.
    if (all_.size() == all_.capacity()) all_.reserve(std::max<std::size_t>(64, 2 * all_.size()));
    auto* b = new OutBlock;
    all_.push_back(b);
    return b;
}

void BlockPool::prewarm(std::size_t count) {
    all_.reserve(all_.size() + count);
    for (std::size_t i = 0; i < count; ++i) {
        auto* b = new OutBlock;
        all_.push_back(b);
        put(b);
    }
}

void BlockPool::put(OutBlock* b) noexcept {
    b->next = free_;
    free_ = b;
    ++free_count_;
}

std::size_t BlockPool::trim(std::size_t keep) noexcept {
    // Marked in place rather than listed, so that giving memory back allocates none.
    constexpr std::uint32_t kReleased = UINT32_MAX;
    std::size_t release = std::min(unused_since_trim_, free_count_);
    release = std::min(release, all_.size() > keep ? all_.size() - keep : 0);
    for (std::size_t i = 0; i < release; ++i) {
        OutBlock* b = free_;
        free_ = b->next;
        b->end = kReleased;
    }
    free_count_ -= release;
    unused_since_trim_ = free_count_;
    if (release != 0) {
        std::erase_if(all_, [](OutBlock* b) {
            if (b->end != kReleased) return false;
            delete b;  // remove_if asks once per block
            return true;
        });
    }
    return release;
}

std::uint8_t* OutQueue::reserve_new_block(BlockPool& pool) {
    OutBlock* b = pool.get();
    if (tail_)
        tail_->next = b;
    else
        head_ = b;
    tail_ = b;
    return b->data;
}

const std::uint8_t* OutQueue::sendable(std::uint64_t limit, std::size_t& size) const noexcept {
    size = 0;
    if (!head_ || limit <= sent_) return nullptr;
    std::uint64_t n = head_->end - head_->begin;
    if (limit - sent_ < n) n = limit - sent_;
    size = static_cast<std::size_t>(n);
    return size ? head_->data + head_->begin : nullptr;
}

void OutQueue::consume(BlockPool& pool, std::size_t n) noexcept {
    sent_ += n;
    head_->begin += static_cast<std::uint32_t>(n);
    while (head_ && head_->begin == head_->end) {
        OutBlock* done = head_;
        if (done == tail_) {
            // Fully drained: give the block back so that idle connections own no output memory.
            head_ = tail_ = nullptr;
        } else {
            head_ = done->next;
        }
        pool.put(done);
    }
}

void OutQueue::clear(BlockPool& pool) noexcept {
    while (head_) {
        OutBlock* next = head_->next;
        pool.put(head_);
        head_ = next;
    }
    tail_ = nullptr;
    sent_ = written_;
}

}  // namespace mbstorm::server
