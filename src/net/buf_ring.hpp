// A provided-buffer ring (IORING_REGISTER_PBUF_RING): `count` buffers of `size` bytes that the
// kernel picks from for recv with IOSQE_BUFFER_SELECT. Give a buffer back with recycle() as
// soon as its bytes are consumed. liburing 2.3 has no io_uring_setup_buf_ring, so the ring
// memory is mapped and registered here.
#pragma once

#include <liburing.h>

#include <cstddef>
#include <cstdint>

namespace mbstorm::net {

class BufRing {
  public:
    BufRing() = default;
    ~BufRing();
    BufRing(const BufRing&) = delete;
    BufRing& operator=(const BufRing&) = delete;

    // count: power of two, <= 32768. Returns 0 or -errno (e.g. -EINVAL on kernels without
    // buffer rings: fall back to plain recv then).
    int init(io_uring* ring, std::uint16_t group_id, unsigned count, unsigned size) noexcept;
    void reset() noexcept;

    bool valid() const noexcept { return br_ != nullptr; }
    std::uint16_t group_id() const noexcept { return group_id_; }
    unsigned count() const noexcept { return count_; }
    unsigned buffer_size() const noexcept { return size_; }
    std::size_t memory_bytes() const noexcept;

    std::uint8_t* buffer(std::uint16_t id) noexcept {
        return data_ + static_cast<std::size_t>(id) * size_;
    }
    // Hands buffer `id` back to the kernel (visible immediately).
    void recycle(std::uint16_t id) noexcept;

    // Buffer id carried in a CQE's flags; only meaningful when has_buffer(flags).
    static bool has_buffer(std::uint32_t cqe_flags) noexcept {
        return (cqe_flags & IORING_CQE_F_BUFFER) != 0;
    }
    static std::uint16_t buffer_id(std::uint32_t cqe_flags) noexcept {
        return static_cast<std::uint16_t>(cqe_flags >> IORING_CQE_BUFFER_SHIFT);
    }

  private:
    io_uring* ring_ = nullptr;
    io_uring_buf_ring* br_ = nullptr;
    std::uint8_t* data_ = nullptr;
    std::size_t ring_bytes_ = 0;
    unsigned count_ = 0;
    unsigned size_ = 0;
    std::uint16_t group_id_ = 0;
};

}  // namespace mbstorm::net
