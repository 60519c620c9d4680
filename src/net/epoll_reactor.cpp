#include "net/epoll_reactor.hpp"

#include <fcntl.h>
#include <liburing.h>
#include <sys/epoll.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <functional>

#include "net/clock.hpp"

namespace mbstorm::net {
namespace {

// Reads per socket per turn before the others get theirs; the rest waits in the ready list.
constexpr int kReadsPerTurn = 4;
constexpr int kEventsPerWait = 256;

bool later(const auto& a, const auto& b) noexcept {
    return a.due_ns > b.due_ns;
}

void make_non_blocking(int fd) noexcept {
    const int flags = ::fcntl(fd, F_GETFL);
    if (flags >= 0 && (flags & O_NONBLOCK) == 0) ::fcntl(fd, F_SETFL, flags | O_NONBLOCK);
}

std::uint32_t buffer_flags(std::uint16_t id, bool more) noexcept {
    return IORING_CQE_F_BUFFER | (static_cast<std::uint32_t>(id) << IORING_CQE_BUFFER_SHIFT) |
           (more ? IORING_CQE_F_MORE : 0u);
}

}  // namespace

EpollReactor::~EpollReactor() {
    if (epoll_fd_ >= 0) ::close(epoll_fd_);
}

int EpollReactor::init() noexcept {
    epoll_fd_ = ::epoll_create1(EPOLL_CLOEXEC);
    if (epoll_fd_ < 0) return -errno;
    try {
        fds_.resize(1024);
        ready_.reserve(1024);
        ready_scratch_.reserve(1024);
        completions_.reserve(1024);
        draining_.reserve(1024);
        timers_.reserve(1024);
    } catch (...) {
        return -ENOMEM;
    }
    return 0;
}

int EpollReactor::init_buffers(unsigned count, unsigned size) noexcept {
    try {
        buffers_.assign(static_cast<std::size_t>(count) * size, 0);
        free_buffers_.clear();
        free_buffers_.reserve(count);
        for (unsigned id = count; id > 0; --id)
            free_buffers_.push_back(static_cast<std::uint16_t>(id - 1));
    } catch (...) {
        return -ENOMEM;
    }
    buffer_size_ = size;
    return 0;
}

EpollReactor::FdState& EpollReactor::state(int fd) noexcept {
    const auto index = static_cast<std::size_t>(fd);
    if (index >= fds_.size()) {
        try {
            fds_.resize(std::max(index + 1, 2 * fds_.size()));
        } catch (...) {
            std::terminate();  // a descriptor table the size of the process's: nothing to save
        }
    }
    return fds_[index];
}

bool EpollReactor::watch(int fd, FdState& s) noexcept {
    if (s.registered) return true;
    epoll_event event{};
    event.events = EPOLLIN | EPOLLOUT | EPOLLRDHUP | EPOLLET;
    event.data.fd = fd;
    if (::epoll_ctl(epoll_fd_, EPOLL_CTL_ADD, fd, &event) != 0 && errno != EEXIST) return false;
    s.registered = true;
    // Not known yet: the first try finds out, the edge after an EAGAIN tells from then on.
    s.readable = s.writable = true;
    return true;
}

void EpollReactor::list_ready(int fd, FdState& s) noexcept {
    if (s.listed) return;
    s.listed = true;
    ready_.push_back(fd);
}

void EpollReactor::complete(std::uint64_t user_data, std::int32_t res,
                            std::uint32_t flags) noexcept {
    completions_.push_back(Completion{user_data, res, flags});
}

void EpollReactor::arm_input(int fd, Input input, const InputTarget& target) noexcept {
    FdState& s = state(fd);
    // Sockets made elsewhere (a listener, an eventfd) may block: never here.
    if (input == Input::Read || input == Input::Accept) make_non_blocking(fd);
    if (!watch(fd, s)) return complete(target.user_data, -errno);
    s.input = input;
    s.input_data = target.user_data;
    s.multishot = target.multishot;
    s.in_ptr = static_cast<std::uint8_t*>(target.data);
    s.in_size = target.size;
    if (s.readable) list_ready(fd, s);
}

void EpollReactor::recv(int fd, std::uint64_t user_data, bool multishot) noexcept {
    arm_input(fd, Input::PoolRecv, InputTarget{user_data, multishot, nullptr, 0});
}

void EpollReactor::recv_into(int fd, void* data, unsigned size, std::uint64_t user_data) noexcept {
    arm_input(fd, Input::RecvInto, InputTarget{user_data, false, data, size});
}

void EpollReactor::read(int fd, void* data, unsigned size, std::uint64_t user_data) noexcept {
    arm_input(fd, Input::Read, InputTarget{user_data, false, data, size});
}

void EpollReactor::accept(int listen_fd, std::uint64_t user_data, bool multishot) noexcept {
    arm_input(listen_fd, Input::Accept, InputTarget{user_data, multishot, nullptr, 0});
}

void EpollReactor::send(int fd, const void* data, unsigned size, std::uint64_t user_data) noexcept {
    FdState& s = state(fd);
    if (!watch(fd, s)) return complete(user_data, -errno);
    s.output = Output::Send;
    s.output_data = user_data;
    s.out_ptr = static_cast<const std::uint8_t*>(data);
    s.out_size = size;
    if (s.writable) run_output(fd, s);  // most sends go at once, as io_uring's inline issue
}

void EpollReactor::connect(int fd, const sockaddr* address, socklen_t length,
                           std::uint64_t user_data, std::int64_t timeout_ns,
                           std::uint64_t timeout_user_data) noexcept {
    FdState& s = state(fd);
    make_non_blocking(fd);
    if (!watch(fd, s)) {
        complete(user_data, -errno);
        return complete(timeout_user_data, -ECANCELED);
    }
    const int rc = ::connect(fd, address, length);
    if (rc == 0 || errno != EINPROGRESS) {
        complete(user_data, rc == 0 ? 0 : -errno);
        return complete(timeout_user_data, -ECANCELED);
    }
    s.output = Output::Connect;
    s.output_data = user_data;
    s.timeout_data = timeout_user_data;
    s.timer = next_token_++;
    s.writable = false;  // the connect's end is the edge to wait for
    add_timer(now_ns() + timeout_ns, s.timer, timeout_user_data, fd);
}

void EpollReactor::timeout(std::int64_t after_ns, std::uint64_t user_data) noexcept {
    add_timer(now_ns() + after_ns, next_token_++, user_data, -1);
}

void EpollReactor::add_timer(std::int64_t due_ns, std::uint64_t token, std::uint64_t user_data,
                             int fd) noexcept {
    timers_.push_back(Timer{due_ns, token, user_data, fd});
    std::push_heap(timers_.begin(), timers_.end(), later<Timer, Timer>);
}

void EpollReactor::cancel_input(int fd, std::uint64_t target, std::uint64_t user_data) noexcept {
    FdState& s = state(fd);
    if (s.input == Input::None || s.input_data != target) return complete(user_data, -ENOENT);
    s.input = Input::None;
    complete(target, -ECANCELED);
    complete(user_data, 0);
}

void EpollReactor::end_operations(int fd, FdState& s) noexcept {
    if (s.input != Input::None) complete(s.input_data, -ECANCELED);
    if (s.output == Output::Connect) {
        finish_connect(fd, s, -ECANCELED);
    } else if (s.output == Output::Send) {
        complete(s.output_data, -ECANCELED);
    }
    s.input = Input::None;
    s.output = Output::None;
}

void EpollReactor::cancel_all(std::uint64_t user_data) noexcept {
    for (std::size_t fd = 0; fd < fds_.size(); ++fd) end_operations(static_cast<int>(fd), fds_[fd]);
    for (const Timer& t : timers_)
        if (t.fd < 0) complete(t.user_data, -ECANCELED);
    timers_.clear();
    complete(user_data, 0);
}

void EpollReactor::close(int fd) noexcept {
    if (fd < 0) return;
    FdState& s = state(fd);
    end_operations(fd, s);
    // The kernel drops a closed socket from the epoll set by itself; the state goes with it.
    s = FdState{};
    ::close(fd);
}

void EpollReactor::run(int fd) noexcept {
    FdState& s = fds_[static_cast<std::size_t>(fd)];
    if (s.input != Input::None && s.readable) run_input(fd, s);
    if (s.output != Output::None && s.writable) run_output(fd, s);
}

void EpollReactor::run_input(int fd, FdState& s) noexcept {
    for (int turn = 0; turn < kReadsPerTurn; ++turn) {
        const bool go_on = s.input == Input::Accept ? accept_once(fd, s) : recv_once(fd, s);
        if (!go_on || s.input == Input::None || !s.readable) return;
    }
    list_ready(fd, s);  // more may be waiting: after the others have had a turn
}

bool EpollReactor::recv_once(int fd, FdState& s) noexcept {
    std::uint8_t* into = s.in_ptr;
    unsigned size = s.in_size;
    std::uint16_t id = 0;
    if (s.input == Input::PoolRecv) {
        if (free_buffers_.empty()) {
            s.input = Input::None;
            complete(s.input_data, -ENOBUFS);
            return false;
        }
        id = free_buffers_.back();
        free_buffers_.pop_back();
        into = buffer(id);
        size = buffer_size_;
    }
    const ssize_t n =
        s.input == Input::Read ? ::read(fd, into, size) : ::recv(fd, into, size, MSG_DONTWAIT);
    const int error = n < 0 ? errno : 0;
    if (s.input == Input::PoolRecv && n <= 0) recycle(id);
    if (n < 0 && (error == EAGAIN || error == EINTR)) {
        s.readable = error == EINTR;
        return error == EINTR;
    }
    const bool more = s.multishot && n > 0;
    const std::uint32_t flags = s.input == Input::PoolRecv && n > 0 ? buffer_flags(id, more) : 0;
    complete(s.input_data, n < 0 ? -error : static_cast<std::int32_t>(n), flags);
    // A stream read short of its buffer emptied the socket: the next arrival is an edge.
    if (n > 0 && static_cast<unsigned>(n) < size && s.input != Input::Read && !s.hangup)
        s.readable = false;
    if (!more) s.input = Input::None;
    return more;
}

bool EpollReactor::accept_once(int fd, FdState& s) noexcept {
    const int socket = ::accept4(fd, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (socket < 0 && (errno == EAGAIN || errno == EINTR)) {
        s.readable = errno == EINTR;
        return s.readable;
    }
    const bool more = s.multishot && socket >= 0;
    complete(s.input_data, socket < 0 ? -errno : socket, more ? IORING_CQE_F_MORE : 0u);
    if (!more) s.input = Input::None;
    return more;
}

void EpollReactor::run_output(int fd, FdState& s) noexcept {
    if (s.output == Output::Connect) {
        int error = 0;
        socklen_t length = sizeof error;
        if (::getsockopt(fd, SOL_SOCKET, SO_ERROR, &error, &length) != 0) error = errno;
        return finish_connect(fd, s, -error);
    }
    for (;;) {
        const ssize_t n = ::send(fd, s.out_ptr, s.out_size, MSG_DONTWAIT | MSG_NOSIGNAL);
        if (n < 0 && errno == EINTR) continue;
        if (n < 0 && errno == EAGAIN) {
            s.writable = false;
            return;
        }
        s.output = Output::None;
        if (n >= 0 && static_cast<unsigned>(n) < s.out_size) s.writable = false;
        return complete(s.output_data, n < 0 ? -errno : static_cast<std::int32_t>(n));
    }
}

void EpollReactor::finish_connect(int fd, FdState& s, std::int32_t res) noexcept {
    (void)fd;
    s.output = Output::None;
    s.timer = 0;  // its heap entry is stale from now on
    s.writable = res == 0;
    complete(s.output_data, res);
    complete(s.timeout_data, -ECANCELED);
}

void EpollReactor::fire_timers(std::int64_t now) noexcept {
    while (!timers_.empty() && timers_.front().due_ns <= now) {
        std::pop_heap(timers_.begin(), timers_.end(), later<Timer, Timer>);
        const Timer t = timers_.back();
        timers_.pop_back();
        if (t.fd < 0) {
            complete(t.user_data, -ETIME);
            continue;
        }
        FdState& s = fds_[static_cast<std::size_t>(t.fd)];
        if (s.output != Output::Connect || s.timer != t.token) continue;  // ended before
        s.output = Output::None;
        s.timer = 0;
        complete(s.output_data, -ECANCELED);
        complete(t.user_data, -ETIME);
    }
}

void EpollReactor::run_ready() noexcept {
    // Runs may list descriptors again (more to read): those wait for the next turn.
    ready_scratch_.swap(ready_);
    for (const int fd : ready_scratch_) {
        fds_[static_cast<std::size_t>(fd)].listed = false;
        run(fd);
    }
    ready_scratch_.clear();
}

int EpollReactor::poll(std::int64_t timeout_ns) noexcept {
    epoll_event events[kEventsPerWait];
    int n = -1;
    if (fine_wait_) {
        timespec ts{timeout_ns / kNsPerSec, timeout_ns % kNsPerSec};
        n = ::epoll_pwait2(epoll_fd_, events, kEventsPerWait, timeout_ns < 0 ? nullptr : &ts,
                           nullptr);
        if (n < 0 && (errno == ENOSYS || errno == EPERM)) fine_wait_ = false;
    }
    if (!fine_wait_) {
        const std::int64_t ms = timeout_ns < 0 ? -1 : (timeout_ns + kNsPerMs - 1) / kNsPerMs;
        n = ::epoll_wait(epoll_fd_, events, kEventsPerWait, static_cast<int>(ms));
    }
    if (n < 0) return errno == EINTR ? 0 : -errno;
    for (int i = 0; i < n; ++i) {
        const int fd = events[i].data.fd;
        FdState& s = state(fd);
        const std::uint32_t e = events[i].events;
        if (e & (EPOLLIN | EPOLLRDHUP | EPOLLERR | EPOLLHUP)) s.readable = true;
        if (e & (EPOLLRDHUP | EPOLLERR | EPOLLHUP)) s.hangup = true;
        if (e & (EPOLLOUT | EPOLLERR | EPOLLHUP)) s.writable = true;
        run(fd);
    }
    return 0;
}

int EpollReactor::wait(std::int64_t timeout_ns) noexcept {
    run_ready();
    std::int64_t now = now_ns();
    fire_timers(now);
    if (!completions_.empty() || !ready_.empty()) timeout_ns = 0;
    if (!timers_.empty()) {
        const std::int64_t until_timer = std::max<std::int64_t>(timers_.front().due_ns - now, 0);
        timeout_ns = timeout_ns < 0 ? until_timer : std::min(timeout_ns, until_timer);
    }
    const int rc = poll(timeout_ns);
    if (rc < 0) return rc;
    fire_timers(now_ns());
    return 0;
}

}  // namespace mbstorm::net
