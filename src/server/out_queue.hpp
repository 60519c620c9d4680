// Per-connection output: a chain of fixed-size blocks taken from a per-thread pool only while
// there is something to send, so an idle connection holds no output memory at all. Blocks
// go back to the pool (never to the heap), so steady-state traffic allocates nothing.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace mbstorm::server {

struct OutBlock {
    static constexpr std::size_t kCapacity = 16 * 1024 - 32;
    OutBlock* next = nullptr;
    std::uint32_t begin = 0;  // first byte not yet sent
    std::uint32_t end = 0;    // one past the last byte written
    std::uint8_t data[kCapacity];
};

class BlockPool {
  public:
    BlockPool() = default;
    ~BlockPool();
    // Allocates `count` blocks up front, so that a steady load within that many busy
    // output blocks per thread never reaches the heap.
    void prewarm(std::size_t count);
    BlockPool(const BlockPool&) = delete;
    BlockPool& operator=(const BlockPool&) = delete;

    OutBlock* get();  // may allocate when the pool is empty
    void put(OutBlock* b) noexcept;
    std::size_t allocated() const noexcept { return all_.size(); }
    std::size_t free_blocks() const noexcept { return free_count_; }

    // Gives back to the heap the free blocks no get() needed since the last trim (a crowd of
    // slow readers gone), keeping at least `keep` blocks allocated; returns how many went.
    // Blocks that kept being used stay pooled, so a steady load is not made to allocate again.
    std::size_t trim(std::size_t keep) noexcept;
    // Whether trim(keep) may release something, now or at a later call.
    bool above(std::size_t keep) const noexcept { return all_.size() > keep; }

  private:
    OutBlock* free_ = nullptr;
    std::size_t free_count_ = 0;
    std::size_t unused_since_trim_ = 0;  // the fewest free blocks since the last trim
    std::vector<OutBlock*> all_;
};

class OutQueue {
  public:
    // Space for one more frame of up to `max_size` bytes at the tail (a new block if needed).
    // Inline: once per answer, and nearly always the tail has room.
    std::uint8_t* reserve(BlockPool& pool, std::size_t max_size) {
        if (tail_ && OutBlock::kCapacity - tail_->end >= max_size) [[likely]]
            return tail_->data + tail_->end;
        return reserve_new_block(pool);
    }
    // Commits `size` bytes written at the pointer reserve() returned.
    void commit(std::size_t size) noexcept {
        tail_->end += static_cast<std::uint32_t>(size);
        written_ += size;
    }

    bool empty() const noexcept { return written_ == sent_; }
    std::size_t bytes() const noexcept { return static_cast<std::size_t>(written_ - sent_); }
    // Stream positions (bytes ever written / sent): a hold is "nothing from position P on".
    std::uint64_t written_position() const noexcept { return written_; }

    // The contiguous bytes at the head that may go out now, stopping at stream position
    // `limit` (UINT64_MAX: no hold).
    const std::uint8_t* sendable(std::uint64_t limit, std::size_t& size) const noexcept;
    // `n` bytes of the head went out: frees fully sent blocks.
    void consume(BlockPool& pool, std::size_t n) noexcept;
    void clear(BlockPool& pool) noexcept;

  private:
    std::uint8_t* reserve_new_block(BlockPool& pool);

    OutBlock* head_ = nullptr;
    OutBlock* tail_ = nullptr;
    std::uint64_t written_ = 0;
    std::uint64_t sent_ = 0;
};

}  // namespace mbstorm::server
