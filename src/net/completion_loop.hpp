// What every io_uring worker loop here repeats, whatever it speaks: arming a recv on a
// provided-buffer group, telling a failed wait from an expected wake-up, and listing each
// connection with output once per loop iteration so it gets one send.
#pragma once

#include <liburing.h>

#include <cerrno>
#include <cstdint>
#include <vector>

namespace mbstorm::net {

// Prepares a recv on `fd` whose buffer the kernel picks from provided-buffer group
// `buf_group`. Multishot: one SQE, a CQE per arrival, until a CQE comes without
// IORING_CQE_F_MORE; otherwise one CQE of at most `buf_size` bytes.
inline void prep_group_recv(io_uring_sqe* sqe, int fd, std::uint16_t buf_group, unsigned buf_size,
                            bool multishot) noexcept {
    if (multishot) {
        io_uring_prep_recv_multishot(sqe, fd, nullptr, 0, 0);
    } else {
        io_uring_prep_recv(sqe, fd, nullptr, buf_size, 0);
    }
    sqe->flags |= IOSQE_BUFFER_SELECT;
    sqe->buf_group = buf_group;
}

// True when Ring::submit_and_wait's result means the ring is broken. A timeout, a signal or
// a full completion queue (-EAGAIN, -EBUSY) only mean "look at the completions and go on".
constexpr bool wait_failed(int rc) noexcept {
    return rc < 0 && rc != -ETIME && rc != -EINTR && rc != -EAGAIN && rc != -EBUSY;
}

// Connections with output to send at the end of this loop iteration, each listed once: the
// connection's own `listed` flag says whether it is in already. Reserve for every connection
// up front and marking never allocates.
class DirtyList {
  public:
    void reserve(std::size_t connections) { indices_.reserve(connections); }

    void mark(bool& listed, std::uint32_t index) {
        if (listed) return;
        listed = true;
        indices_.push_back(index);
    }

    // Calls fn(index) for every listed connection, in marking order, then empties the list.
    // fn clears the connection's flag.
    template <class Fn>
    void drain(Fn&& fn) {
        for (const std::uint32_t index : indices_) fn(index);
        indices_.clear();
    }

  private:
    std::vector<std::uint32_t> indices_;
};

}  // namespace mbstorm::net
