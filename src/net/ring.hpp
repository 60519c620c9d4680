// RAII over one io_uring. One ring per thread; the ring is used only by the thread that
// created it when single_issuer is on (the default when the kernel has it).
#pragma once

#include <liburing.h>

#include <cstdint>

namespace mbstorm::net {

struct RingOptions {
    unsigned entries = 4096;    // SQ size
    unsigned cq_entries = 0;    // 0 -> 4 * entries (multishot ops produce many CQEs)
    bool single_issuer = true;  // use IORING_SETUP_SINGLE_ISSUER when available
    bool defer_taskrun = true;  // use IORING_SETUP_DEFER_TASKRUN when available
    bool coop_taskrun = true;   // use IORING_SETUP_COOP_TASKRUN (+TASKRUN_FLAG) when available
};

class Ring {
  public:
    Ring() = default;
    ~Ring();
    Ring(const Ring&) = delete;
    Ring& operator=(const Ring&) = delete;
    Ring(Ring&& other) noexcept;
    Ring& operator=(Ring&& other) noexcept;

    // Tries the requested flags, dropping the unsupported ones one by one: 0 or -errno.
    int init(const RingOptions& options = {}) noexcept;
    void reset() noexcept;

    bool valid() const noexcept { return initialized_; }
    io_uring* get() noexcept { return &ring_; }
    unsigned setup_flags() const noexcept { return setup_flags_; }

    // A free SQE; when the SQ is full it submits first. Never null on a valid ring unless
    // submission itself fails (then nullptr).
    io_uring_sqe* sqe() noexcept;

    int submit() noexcept { return io_uring_submit(&ring_); }
    // Submits and waits for at least `wait_nr` CQEs or until `timeout_ns` passes (-1 = no
    // timeout). Returns >= 0, -ETIME on timeout, -EINTR, or another -errno.
    int submit_and_wait(unsigned wait_nr, std::int64_t timeout_ns = -1) noexcept;

    // Calls fn(const io_uring_cqe&) for every ready CQE, then marks them seen. Returns count.
    template <class Fn>
    unsigned drain(Fn&& fn) noexcept {
        unsigned head;
        unsigned count = 0;
        io_uring_cqe* cqe;
        io_uring_for_each_cqe(&ring_, head, cqe) {
            fn(*cqe);
            ++count;
        }
        io_uring_cq_advance(&ring_, count);
        return count;
    }

  private:
    io_uring ring_{};
    unsigned setup_flags_ = 0;
    bool initialized_ = false;
};

}  // namespace mbstorm::net
