// io_uring's completion model over epoll, for processes where io_uring is refused (Docker 25+
// and containerd 2.0 default seccomp profiles, "restricted" Kubernetes pods,
// kernel.io_uring_disabled). Each operation is carried out with a non-blocking call when its
// socket is ready, and its outcome is queued as a completion with io_uring's fields (result,
// IORING_CQE_F_MORE, IORING_CQE_F_BUFFER and a buffer id), so the workers above handle one
// kind of event whatever the backend (see event_loop.hpp).
//
// Sockets are registered edge-triggered once; what is known of their readiness is kept and
// an operation is tried at once when its side is (or may be) ready. At most one input
// operation (accept, recv, read) and one output operation (send, connect) per descriptor, as
// the workers use io_uring.
#pragma once

#include <sys/socket.h>

#include <cstdint>
#include <vector>

namespace mbstorm::net {

// One finished operation, as io_uring reports it: user_data, the result (bytes, a descriptor,
// 0, or -errno) and IORING_CQE_F_* flags.
struct Completion {
    std::uint64_t user_data = 0;
    std::int32_t res = 0;
    std::uint32_t flags = 0;
};

class EpollReactor {
  public:
    EpollReactor() = default;
    ~EpollReactor();
    EpollReactor(const EpollReactor&) = delete;
    EpollReactor& operator=(const EpollReactor&) = delete;

    int init() noexcept;  // 0 or -errno
    bool valid() const noexcept { return epoll_fd_ >= 0; }

    // The provided buffers recv() picks from: `count` of `size` bytes. 0 or -ENOMEM.
    int init_buffers(unsigned count, unsigned size) noexcept;
    std::uint8_t* buffer(std::uint16_t id) noexcept {
        return buffers_.data() + static_cast<std::size_t>(id) * buffer_size_;
    }
    void recycle(std::uint16_t id) noexcept { free_buffers_.push_back(id); }
    unsigned buffer_size() const noexcept { return buffer_size_; }
    std::size_t memory_bytes() const noexcept { return buffers_.size(); }

    // Reads into a provided buffer; multishot: a completion per arrival until one without
    // IORING_CQE_F_MORE (end of stream, an error, or -ENOBUFS when the buffers ran out).
    void recv(int fd, std::uint64_t user_data, bool multishot) noexcept;
    // One read into the caller's memory: recv(2) on a socket, read(2) otherwise (an eventfd).
    void recv_into(int fd, void* data, unsigned size, std::uint64_t user_data) noexcept;
    void read(int fd, void* data, unsigned size, std::uint64_t user_data) noexcept;
    // Sends what it can now or once writable: the completion carries the count (maybe short).
    void send(int fd, const void* data, unsigned size, std::uint64_t user_data) noexcept;
    // Connects `fd` (made non-blocking here). The timeout's completion says -ETIME when it
    // fired (the connect then ends -ECANCELED) and -ECANCELED when the connect ended first,
    // as with an io_uring linked timeout.
    void connect(int fd, const sockaddr* address, socklen_t length, std::uint64_t user_data,
                 std::int64_t timeout_ns, std::uint64_t timeout_user_data) noexcept;
    // Accepted sockets are non-blocking and close-on-exec.
    void accept(int listen_fd, std::uint64_t user_data, bool multishot) noexcept;
    void timeout(std::int64_t after_ns, std::uint64_t user_data) noexcept;
    // Ends the input operation with `target` on `fd` (-ECANCELED); the cancel's own completion
    // is 0, or -ENOENT when there was none.
    void cancel_input(int fd, std::uint64_t target, std::uint64_t user_data) noexcept;
    // Ends every pending operation and timeout (-ECANCELED), as IORING_ASYNC_CANCEL_ANY.
    void cancel_all(std::uint64_t user_data) noexcept;
    // Ends `fd`'s pending operations (-ECANCELED) and closes it.
    void close(int fd) noexcept;

    // Carries out what is ready, waiting up to `timeout_ns` (-1: no limit) when nothing is
    // complete yet. 0 or -errno.
    int wait(std::int64_t timeout_ns) noexcept;
    bool has_completions() const noexcept { return !completions_.empty(); }

    // Calls fn(const Completion&) for each completion, oldest first; completions queued by fn
    // wait for the next call. Returns the count.
    template <class Fn>
    unsigned drain(Fn&& fn) {
        draining_.swap(completions_);
        for (const Completion& c : draining_) fn(c);
        const auto count = static_cast<unsigned>(draining_.size());
        draining_.clear();
        return count;
    }

  private:
    enum class Input : std::uint8_t { None, PoolRecv, RecvInto, Read, Accept };
    enum class Output : std::uint8_t { None, Send, Connect };
    struct FdState {
        bool registered = false;
        bool readable = false;  // may be: tried until EAGAIN says otherwise
        bool writable = false;
        // The peer closed or the socket failed: its end of stream or error is queued behind
        // any data, with no edge to come, so a short read no longer means "drained".
        bool hangup = false;
        bool listed = false;  // in ready_
        Input input = Input::None;
        bool multishot = false;
        Output output = Output::None;
        std::uint64_t input_data = 0;
        std::uint64_t output_data = 0;
        std::uint64_t timeout_data = 0;  // the connect's linked timeout
        std::uint64_t timer = 0;         // its token in timers_ (0: none)
        std::uint8_t* in_ptr = nullptr;
        unsigned in_size = 0;
        const std::uint8_t* out_ptr = nullptr;
        unsigned out_size = 0;
    };
    struct Timer {
        std::int64_t due_ns;
        std::uint64_t token;
        std::uint64_t user_data;
        int fd;  // a connect's timeout: its descriptor; -1 for a plain timeout
    };

    struct InputTarget {
        std::uint64_t user_data;
        bool multishot;
        void* data;  // RecvInto and Read: the caller's memory
        unsigned size;
    };
    void arm_input(int fd, Input input, const InputTarget& target) noexcept;
    FdState& state(int fd) noexcept;
    bool watch(int fd, FdState& s) noexcept;  // registers once; false when epoll refused
    void list_ready(int fd, FdState& s) noexcept;
    void complete(std::uint64_t user_data, std::int32_t res, std::uint32_t flags = 0) noexcept;
    void run(int fd) noexcept;
    void run_input(int fd, FdState& s) noexcept;
    bool recv_once(int fd, FdState& s) noexcept;  // false: stop reading this socket now
    bool accept_once(int fd, FdState& s) noexcept;
    void run_output(int fd, FdState& s) noexcept;
    void finish_connect(int fd, FdState& s, std::int32_t res) noexcept;
    void end_operations(int fd, FdState& s) noexcept;
    void add_timer(std::int64_t due_ns, std::uint64_t token, std::uint64_t user_data,
                   int fd) noexcept;
    void fire_timers(std::int64_t now) noexcept;
    void run_ready() noexcept;
    int poll(std::int64_t timeout_ns) noexcept;

    int epoll_fd_ = -1;
    std::vector<FdState> fds_;
    std::vector<int> ready_;  // descriptors to try without waiting for an event
    std::vector<int> ready_scratch_;
    std::vector<Completion> completions_;
    std::vector<Completion> draining_;
    std::vector<Timer> timers_;  // min-heap on due_ns
    std::uint64_t next_token_ = 1;
    std::vector<std::uint8_t> buffers_;
    std::vector<std::uint16_t> free_buffers_;
    unsigned buffer_size_ = 0;
    bool fine_wait_ = true;  // epoll_pwait2 works (else epoll_wait's milliseconds)
};

}  // namespace mbstorm::net
