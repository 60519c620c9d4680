// The worker's connections by index: stable addresses (a Connection is never moved), grown in
// chunks of 64 built on demand, never shrunk. Indexing is a shift, a mask and two loads;
// std::deque's (one ~400-byte Connection per node) cost about 8 instructions per lookup, and
// the hot path looks a connection up several times per recv and send.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <vector>

#include "server/connection.hpp"

namespace mbstorm::server {

class ConnectionTable {
  public:
    ConnectionTable() = default;
    ConnectionTable(const ConnectionTable&) = delete;
    ConnectionTable& operator=(const ConnectionTable&) = delete;
    ~ConnectionTable() {
        for (std::uint32_t i = 0; i < size_; ++i) (*this)[i].~Connection();
    }

    std::uint32_t size() const noexcept { return size_; }
    Connection& operator[](std::uint32_t index) noexcept {
        return std::launder(
            reinterpret_cast<Connection*>(chunks_[index >> kChunkBits]->bytes))[index & kChunkMask];
    }
    const Connection& operator[](std::uint32_t index) const noexcept {
        return std::launder(reinterpret_cast<const Connection*>(
            chunks_[index >> kChunkBits]->bytes))[index & kChunkMask];
    }
    // A new default connection at index size() - 1. May throw std::bad_alloc (nothing changes).
    Connection& emplace_back() {
        if ((size_ >> kChunkBits) == chunks_.size()) chunks_.push_back(std::make_unique<Chunk>());
        Connection* slot = reinterpret_cast<Connection*>(chunks_[size_ >> kChunkBits]->bytes) +
                           (size_ & kChunkMask);
        new (slot) Connection();
        ++size_;
        return *slot;
    }

  private:
    static constexpr unsigned kChunkBits = 6;
    static constexpr std::uint32_t kChunkMask = (1u << kChunkBits) - 1;
    struct Chunk {
        alignas(Connection) std::byte bytes[sizeof(Connection) << kChunkBits];
    };
    std::vector<std::unique_ptr<Chunk>> chunks_;
    std::uint32_t size_ = 0;
};

}  // namespace mbstorm::server
