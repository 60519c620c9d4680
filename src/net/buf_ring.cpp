#include "net/buf_ring.hpp"

#include <sys/mman.h>

#include <cerrno>

namespace mbstorm::net {

BufRing::~BufRing() {
    reset();
}

void BufRing::reset() noexcept {
    if (br_) {
        io_uring_unregister_buf_ring(ring_, group_id_);
        munmap(br_, ring_bytes_);
        br_ = nullptr;
    }
    if (data_) {
        munmap(data_, static_cast<std::size_t>(count_) * size_);
        data_ = nullptr;
    }
    count_ = size_ = 0;
}

std::size_t BufRing::memory_bytes() const noexcept {
    return ring_bytes_ + static_cast<std::size_t>(count_) * size_;
}

int BufRing::init(io_uring* ring, std::uint16_t group_id, unsigned count, unsigned size) noexcept {
    reset();
    if (count == 0 || count > 32768 || (count & (count - 1)) != 0 || size == 0) return -EINVAL;
    ring_ = ring;
    group_id_ = group_id;
    ring_bytes_ = static_cast<std::size_t>(count) * sizeof(io_uring_buf);
    void* r =
        mmap(nullptr, ring_bytes_, PROT_READ | PROT_WRITE, MAP_ANONYMOUS | MAP_PRIVATE, -1, 0);
    if (r == MAP_FAILED) return -errno;
    void* d = mmap(nullptr, static_cast<std::size_t>(count) * size, PROT_READ | PROT_WRITE,
                   MAP_ANONYMOUS | MAP_PRIVATE, -1, 0);
    if (d == MAP_FAILED) {
        int e = errno;
        munmap(r, ring_bytes_);
        return -e;
    }
    io_uring_buf_reg reg{};
    reg.ring_addr = reinterpret_cast<std::uint64_t>(r);
    reg.ring_entries = count;
    reg.bgid = group_id;
    int rc = io_uring_register_buf_ring(ring, &reg, 0);
    if (rc != 0) {
        munmap(r, ring_bytes_);
        munmap(d, static_cast<std::size_t>(count) * size);
        return rc;
    }
    br_ = static_cast<io_uring_buf_ring*>(r);
    data_ = static_cast<std::uint8_t*>(d);
    count_ = count;
    size_ = size;
    io_uring_buf_ring_init(br_);
    const int mask = io_uring_buf_ring_mask(count);
    for (unsigned i = 0; i < count; ++i)
        io_uring_buf_ring_add(br_, buffer(static_cast<std::uint16_t>(i)), size,
                              static_cast<unsigned short>(i), mask, static_cast<int>(i));
    io_uring_buf_ring_advance(br_, static_cast<int>(count));
    return 0;
}

void BufRing::recycle(std::uint16_t id) noexcept {
    io_uring_buf_ring_add(br_, buffer(id), size_, id, io_uring_buf_ring_mask(count_), 0);
    io_uring_buf_ring_advance(br_, 1);
}

}  // namespace mbstorm::net
