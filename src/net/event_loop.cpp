#include "net/event_loop.hpp"

#include <sys/socket.h>
#include <unistd.h>

#include "net/clock.hpp"
#include "net/completion_loop.hpp"
#include "net/direct_socket.hpp"

namespace mbstorm::net {

Error EventLoop::init(Backend backend, const RingOptions& options) noexcept {
    backend_ = backend;
    const int rc = uses_io_uring() ? ring_.init(options) : epoll_.init();
    if (rc >= 0) return {};
    return from_errno(ErrorCode::Unsupported, -rc, "");
}

Error EventLoop::init_buffers(std::uint16_t group, unsigned count, unsigned size) noexcept {
    const int rc = uses_io_uring() ? buf_ring_.init(ring_.get(), group, count, size)
                                   : epoll_.init_buffers(count, size);
    if (rc >= 0) return {};
    return from_errno(ErrorCode::Unsupported, -rc, "");
}

bool EventLoop::has_buffers() const noexcept {
    return uses_io_uring() ? buf_ring_.valid() : epoll_.buffer_size() != 0;
}

unsigned EventLoop::buffer_size() const noexcept {
    return uses_io_uring() ? buf_ring_.buffer_size() : epoll_.buffer_size();
}

std::size_t EventLoop::buffer_memory_bytes() const noexcept {
    return uses_io_uring() ? buf_ring_.memory_bytes() : epoll_.memory_bytes();
}

bool EventLoop::recv(int fd, std::uint64_t user_data, bool multishot) noexcept {
    if (!uses_io_uring()) {
        epoll_.recv(fd, user_data, multishot);
        return true;
    }
    io_uring_sqe* s = ring_.sqe();
    if (s == nullptr) return false;
    prep_group_recv(s, fd, buf_ring_.group_id(), buf_ring_.buffer_size(), multishot);
    use_slot_if(s, direct_);
    io_uring_sqe_set_data64(s, user_data);
    return true;
}

bool EventLoop::recv_into(int fd, void* data, unsigned size, std::uint64_t user_data) noexcept {
    if (!uses_io_uring()) {
        epoll_.recv_into(fd, data, size, user_data);
        return true;
    }
    io_uring_sqe* s = ring_.sqe();
    if (s == nullptr) return false;
    io_uring_prep_recv(s, fd, data, size, 0);
    use_slot_if(s, direct_);
    io_uring_sqe_set_data64(s, user_data);
    return true;
}

bool EventLoop::read(int fd, void* data, unsigned size, std::uint64_t user_data) noexcept {
    if (!uses_io_uring()) {
        epoll_.read(fd, data, size, user_data);
        return true;
    }
    io_uring_sqe* s = ring_.sqe();
    if (s == nullptr) return false;
    io_uring_prep_read(s, fd, data, size, 0);
    io_uring_sqe_set_data64(s, user_data);
    return true;
}

bool EventLoop::send(int fd, const void* data, unsigned size, std::uint64_t user_data) noexcept {
    if (!uses_io_uring()) {
        epoll_.send(fd, data, size, user_data);
        return true;
    }
    io_uring_sqe* s = ring_.sqe();
    if (s == nullptr) return false;
    io_uring_prep_send(s, fd, data, size, MSG_NOSIGNAL);
    use_slot_if(s, direct_);
    io_uring_sqe_set_data64(s, user_data);
    return true;
}

bool EventLoop::connect(int fd, const sockaddr* address, socklen_t length, std::uint64_t user_data,
                        __kernel_timespec* timeout, std::uint64_t timeout_user_data) noexcept {
    if (!uses_io_uring()) {
        const std::int64_t ns = timeout->tv_sec * kNsPerSec + timeout->tv_nsec;
        epoll_.connect(fd, address, length, user_data, ns, timeout_user_data);
        return true;
    }
    // The connect and its linked timeout must reach the kernel in the same submission.
    if (io_uring_sq_space_left(ring_.get()) < 2) ring_.submit();
    io_uring_sqe* s = ring_.sqe();
    if (s == nullptr) return false;
    io_uring_prep_connect(s, fd, address, length);
    use_slot_if(s, direct_);
    io_uring_sqe_set_data64(s, user_data);
    s->flags |= IOSQE_IO_LINK;
    io_uring_sqe* t = ring_.sqe();
    io_uring_prep_link_timeout(t, timeout, 0);
    io_uring_sqe_set_data64(t, timeout_user_data);
    return true;
}

bool EventLoop::accept(int listen_fd, std::uint64_t user_data, bool multishot) noexcept {
    if (!uses_io_uring()) {
        epoll_.accept(listen_fd, user_data, multishot);
        return true;
    }
    io_uring_sqe* s = ring_.sqe();
    if (s == nullptr) return false;
    if (multishot && direct_)
        io_uring_prep_multishot_accept_direct(s, listen_fd, nullptr, nullptr, 0);
    else if (multishot)
        io_uring_prep_multishot_accept(s, listen_fd, nullptr, nullptr, SOCK_CLOEXEC);
    else if (direct_)
        io_uring_prep_accept_direct(s, listen_fd, nullptr, nullptr, 0, kAnySlot);
    else
        io_uring_prep_accept(s, listen_fd, nullptr, nullptr, SOCK_CLOEXEC);
    io_uring_sqe_set_data64(s, user_data);
    return true;
}

bool EventLoop::timeout(__kernel_timespec* after, std::uint64_t user_data) noexcept {
    if (!uses_io_uring()) {
        epoll_.timeout(after->tv_sec * kNsPerSec + after->tv_nsec, user_data);
        return true;
    }
    io_uring_sqe* s = ring_.sqe();
    if (s == nullptr) return false;
    io_uring_prep_timeout(s, after, 0, 0);
    io_uring_sqe_set_data64(s, user_data);
    return true;
}

bool EventLoop::cancel_input(int fd, std::uint64_t target, std::uint64_t user_data) noexcept {
    if (!uses_io_uring()) {
        epoll_.cancel_input(fd, target, user_data);
        return true;
    }
    io_uring_sqe* s = ring_.sqe();
    if (s == nullptr) return false;
    io_uring_prep_cancel64(s, target, 0);
    io_uring_sqe_set_data64(s, user_data);
    return true;
}

bool EventLoop::cancel_all(std::uint64_t user_data) noexcept {
    if (!uses_io_uring()) {
        epoll_.cancel_all(user_data);
        return true;
    }
    io_uring_sqe* s = ring_.sqe();
    if (s == nullptr) return false;
    io_uring_prep_cancel64(s, 0, IORING_ASYNC_CANCEL_ANY);
    io_uring_sqe_set_data64(s, user_data);
    return true;
}

void EventLoop::shutdown_and_close(int fd) noexcept {
    if (fd < 0) return;
    ::shutdown(fd, SHUT_RDWR);  // ends a pending io_uring multishot recv
    close(fd);
}

void EventLoop::close(int fd) noexcept {
    if (fd < 0) return;
    if (uses_io_uring()) {
        ::close(fd);
    } else {
        epoll_.close(fd);
    }
}

bool EventLoop::shutdown_and_close_slot(unsigned slot, std::uint64_t shutdown_data,
                                        std::uint64_t close_data) noexcept {
    // Both SQEs in one submission: the close is linked to the shutdown.
    if (io_uring_sq_space_left(ring_.get()) < 2) ring_.submit();
    io_uring_sqe* shutdown_sqe = ring_.sqe();
    io_uring_sqe* close_sqe = ring_.sqe();
    if (shutdown_sqe == nullptr || close_sqe == nullptr) return false;
    prep_shutdown_and_close(shutdown_sqe, close_sqe, slot, shutdown_data, close_data);
    return true;
}

}  // namespace mbstorm::net
