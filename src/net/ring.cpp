#include "net/ring.hpp"

#include <cerrno>
#include <utility>

#include "net/clock.hpp"

namespace mbstorm::net {

Ring::~Ring() {
    reset();
}

Ring::Ring(Ring&& other) noexcept
    : ring_(other.ring_), setup_flags_(other.setup_flags_), initialized_(other.initialized_) {
    other.initialized_ = false;
}

Ring& Ring::operator=(Ring&& other) noexcept {
    if (this != &other) {
        reset();
        ring_ = other.ring_;
        setup_flags_ = other.setup_flags_;
        initialized_ = std::exchange(other.initialized_, false);
    }
    return *this;
}

void Ring::reset() noexcept {
    if (initialized_) {
        io_uring_queue_exit(&ring_);
        initialized_ = false;
    }
}

int Ring::init(const RingOptions& options) noexcept {
    reset();
    unsigned base = IORING_SETUP_CQSIZE;
    unsigned wanted = 0;
    if (options.single_issuer) wanted |= IORING_SETUP_SINGLE_ISSUER;
    if (options.defer_taskrun && options.single_issuer) wanted |= IORING_SETUP_DEFER_TASKRUN;
    if (options.coop_taskrun && !(wanted & IORING_SETUP_DEFER_TASKRUN))
        wanted |= IORING_SETUP_COOP_TASKRUN | IORING_SETUP_TASKRUN_FLAG;

    // Older kernels reject unknown flags with EINVAL: drop the newest first and retry.
    const unsigned drop_order[] = {IORING_SETUP_DEFER_TASKRUN, IORING_SETUP_SINGLE_ISSUER,
                                   IORING_SETUP_COOP_TASKRUN | IORING_SETUP_TASKRUN_FLAG, 0};
    unsigned flags = wanted;
    int rc = -EINVAL;
    for (unsigned drop : drop_order) {
        io_uring_params params{};
        params.flags = base | flags;
        params.cq_entries = options.cq_entries ? options.cq_entries : options.entries * 4;
        rc = io_uring_queue_init_params(options.entries, &ring_, &params);
        if (rc == 0) {
            setup_flags_ = params.flags;
            initialized_ = true;
            return 0;
        }
        if (rc != -EINVAL) return rc;
        flags &= ~drop;
        // Defer task-run lost means cooperative task-run is worth asking for instead.
        if (drop == IORING_SETUP_DEFER_TASKRUN && options.coop_taskrun)
            flags |= IORING_SETUP_COOP_TASKRUN | IORING_SETUP_TASKRUN_FLAG;
    }
    return rc;
}

io_uring_sqe* Ring::sqe() noexcept {
    io_uring_sqe* s = io_uring_get_sqe(&ring_);
    if (s) return s;
    if (io_uring_submit(&ring_) < 0) return nullptr;
    return io_uring_get_sqe(&ring_);
}

int Ring::submit_and_wait(unsigned wait_nr, std::int64_t timeout_ns) noexcept {
    if (timeout_ns < 0) return io_uring_submit_and_wait(&ring_, wait_nr);
    __kernel_timespec ts{};
    std::int64_t sec;
    long long nsec;
    ns_to_timespec(timeout_ns, sec, nsec);
    ts.tv_sec = sec;
    ts.tv_nsec = nsec;
    io_uring_cqe* cqe = nullptr;
    return io_uring_submit_and_wait_timeout(&ring_, &cqe, wait_nr, &ts, nullptr);
}

}  // namespace mbstorm::net
