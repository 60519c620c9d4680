// The event-source seam of the io_uring workers: one set of operations (accept, connect, recv
// from provided buffers, send, timeouts, cancels) and one kind of completion, carried by
// io_uring where the process may use it and by epoll where it may not (EpollReactor). The
// backend is chosen once, when the loop is set up; each operation asks it with one predictable
// branch, so the io_uring path keeps its batching and pays no virtual call.
#pragma once

#include <liburing.h>

#include <cstdint>
#include "net/backend.hpp"
#include "net/buf_ring.hpp"
#include "net/epoll_reactor.hpp"
#include "net/ring.hpp"
#include "util/error.hpp"

namespace mbstorm::net {

class EventLoop {
  public:
    // Sets the backend up; an Unsupported error says the system's reason (the caller adds what
    // it was setting up). With epoll, `options` is unused.
    Error init(Backend backend, const RingOptions& options) noexcept;
    Backend backend() const noexcept { return backend_; }
    bool uses_io_uring() const noexcept { return backend_ == Backend::IoUring; }
    // io_uring only: for registering tables and probing (nullptr with epoll).
    io_uring* ring() noexcept { return uses_io_uring() ? ring_.get() : nullptr; }

    // Provided buffers for recv(): a buffer ring with io_uring, a pool with epoll; an
    // Unsupported error with the system's reason.
    Error init_buffers(std::uint16_t group, unsigned count, unsigned size) noexcept;
    bool has_buffers() const noexcept;
    std::uint8_t* buffer(std::uint16_t id) noexcept {
        return uses_io_uring() ? buf_ring_.buffer(id) : epoll_.buffer(id);
    }
    void recycle(std::uint16_t id) noexcept {
        if (uses_io_uring()) {
            buf_ring_.recycle(id);
        } else {
            epoll_.recycle(id);
        }
    }
    unsigned buffer_size() const noexcept;
    std::size_t buffer_memory_bytes() const noexcept;

    // Sockets are slots of the ring's registered table (io_uring only).
    void set_direct(bool direct) noexcept { direct_ = direct && uses_io_uring(); }
    bool direct() const noexcept { return direct_; }

    // Each returns false when no operation could be queued (a full submission queue whose
    // submission failed); its completion then never comes.
    bool recv(int fd, std::uint64_t user_data, bool multishot) noexcept;
    bool recv_into(int fd, void* data, unsigned size, std::uint64_t user_data) noexcept;
    bool read(int fd, void* data, unsigned size, std::uint64_t user_data) noexcept;
    bool send(int fd, const void* data, unsigned size, std::uint64_t user_data) noexcept;
    // A connect and its timeout (two completions, as an io_uring linked timeout). `timeout`
    // must outlive the submission.
    bool connect(int fd, const sockaddr* address, socklen_t length, std::uint64_t user_data,
                 __kernel_timespec* timeout, std::uint64_t timeout_user_data) noexcept;
    // Direct: the kernel picks a free slot of the table.
    bool accept(int listen_fd, std::uint64_t user_data, bool multishot) noexcept;
    bool timeout(__kernel_timespec* after, std::uint64_t user_data) noexcept;
    // Cancels the pending input operation with `target` on `fd`.
    bool cancel_input(int fd, std::uint64_t target, std::uint64_t user_data) noexcept;
    bool cancel_all(std::uint64_t user_data) noexcept;
    // A plain descriptor: shut down (its pending receive ends) and closed. With epoll the
    // pending operations end -ECANCELED. Not for direct slots: shutdown_and_close_slot.
    void shutdown_and_close(int fd) noexcept;
    void close(int fd) noexcept;  // without the shutdown
    // Direct only: two completions, the slot free once the close has completed. False when
    // the submission queue had no room.
    bool shutdown_and_close_slot(unsigned slot, std::uint64_t shutdown_data,
                                 std::uint64_t close_data) noexcept;

    int submit() noexcept { return uses_io_uring() ? ring_.submit() : 0; }
    // Waits for a completion or `timeout_ns` (-1: none); see net::wait_failed for the result.
    int submit_and_wait(unsigned wait_nr, std::int64_t timeout_ns) noexcept {
        return uses_io_uring() ? ring_.submit_and_wait(wait_nr, timeout_ns)
                               : epoll_.wait(timeout_ns);
    }
    // Calls fn(const Completion&) for every completion ready now.
    template <class Fn>
    unsigned drain(Fn&& fn) {
        if (!uses_io_uring()) return epoll_.drain(fn);
        return ring_.drain([&fn](const io_uring_cqe& cqe) {
            fn(Completion{cqe.user_data, cqe.res, cqe.flags});
        });
    }

  private:
    Backend backend_ = Backend::IoUring;
    bool direct_ = false;
    Ring ring_;
    BufRing buf_ring_;  // after ring_: unregistered before the ring goes
    EpollReactor epoll_;
};

}  // namespace mbstorm::net
