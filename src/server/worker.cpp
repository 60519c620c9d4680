#include "server/worker.hpp"

#include <malloc.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>

#include "codec/bytes.hpp"
#include "codec/limits.hpp"
#include "net/clock.hpp"
#include "net/direct_socket.hpp"
#include "net/features.hpp"
#include "net/kernel_tls.hpp"
#include "net/socket.hpp"
#include "net/user_data.hpp"
#include "slave/handler.hpp"

namespace mbstorm::server {

namespace {

constexpr std::uint16_t kBufGroup = 1;
constexpr std::int64_t kStopDrainNs = 2 * net::kNsPerSec;
// Out of file descriptors, an accept fails at once until one is freed: wait this long before
// trying again, doubling up to the maximum while it keeps failing.
constexpr std::int64_t kAcceptPauseMinNs = 10 * net::kNsPerMs;
constexpr std::int64_t kAcceptPauseMaxNs = 500 * net::kNsPerMs;

}  // namespace

Worker::Worker(const ServerConfig& config, slave::DataModel& model, int listen_fd, unsigned index,
               std::atomic<std::uint32_t>& open_connections, std::uint64_t stall_origin_ns)
    : config_(config),
      model_(model),
      units_(config.units),
      listen_fd_(listen_fd),
      index_(index),
      open_connections_(open_connections),
      faults_(config.faults, index, stall_origin_ns) {
    plain_frames_ = !units_ && !config_.only_unit && config_.max_outstanding == 0 &&
                    !faults_.enabled() && config_.framing == codec::Framing::Mbap;
    // The transport is chosen here, once: each connection's link knows it from now on.
    link_kind_ = config_.tls                              ? Link::Kind::Tls
                 : config_.framing == codec::Framing::Rtu ? Link::Kind::Rtu
                                                          : Link::Kind::Mbap;
    stop_fd_ = eventfd(0, EFD_CLOEXEC);
    mail_fd_ = eventfd(0, EFD_CLOEXEC);
}

Worker::~Worker() {
    if (stop_fd_ >= 0) ::close(stop_fd_);
    if (mail_fd_ >= 0) ::close(mail_fd_);
    if (listen_fd_ >= 0) ::close(listen_fd_);
}

void Worker::request_stop() noexcept {
    std::uint64_t one = 1;
    if (stop_fd_ >= 0) {
        [[maybe_unused]] auto n = ::write(stop_fd_, &one, sizeof one);
    }
}

Error Worker::setup() noexcept {
    if (stop_fd_ < 0) return from_errno(ErrorCode::Unsupported, EMFILE, "");
    const net::Features& f = net::features();
    net::RingOptions ro;
    ro.entries = config_.ring_entries;
    if (Error e = loop_.init(config_.backend, ro); !e.ok()) return e;
    // epoll emulates buffer rings and multishot operations whatever the kernel has.
    const bool uring = loop_.uses_io_uring();
    use_buf_ring_ = config_.use_buf_ring && (f.buf_ring || !uring) &&
                    loop_.init_buffers(kBufGroup, config_.buf_ring_count, config_.buf_size).ok();
    multishot_recv_ = use_buf_ring_ && config_.use_multishot_recv && (f.multishot_recv || !uring);
    multishot_accept_ = config_.use_multishot_accept && (f.multishot_accept || !uring);
    // The kernel's TLS needs a socket setsockopt can reach (not a direct descriptor) and a
    // hand-off with no recv in flight (single-shot recvs): worth more than either.
    ktls_ = config_.tls && net::kernel_tls().available;
    if (ktls_) multishot_recv_ = false;
    direct_ = uring && !ktls_ && table_slots_ > 0 &&
              net::register_socket_table(loop_.ring(), table_slots_).ok();
    loop_.set_direct(direct_);
    try {
        std::size_t expect = config_.max_connections ? config_.max_connections : 1024;
        expect = std::min<std::size_t>(expect, 65536);
        free_slots_.reserve(expect);
        dirty_.reserve(expect);
        rearm_.reserve(expect);
        held_.reserve(expect);
        partial_.reserve(expect);
        pool_.prewarm(config_.prealloc_output_blocks);
        if (link_kind_ == Link::Kind::Tls)
            link_scratch_.resize(16 * 1024);  // one TLS record's plaintext at most
        if (use_buf_ring_) {
            stash_next_.assign(config_.buf_ring_count, kNoBuffer);
            stash_size_.assign(config_.buf_ring_count, 0);
        }
    } catch (...) {
        return from_errno(ErrorCode::Unsupported, ENOMEM, "");
    }
    accept_pause_ns_ = kAcceptPauseMinNs;
    arm_accept();
    arm_stop();
    cross_evict_ = peers_.size() > 1 && config_.max_connections != 0 &&
                   config_.full_policy == FullPolicy::EvictOldestIdle && mail_fd_ >= 0;
    if (cross_evict_) arm_mail();
    loop_.submit();
    return {};
}

void Worker::run() noexcept {
    setup_error_ = setup();
    init_status_.store(setup_error_.ok() ? 1 : -1, std::memory_order_release);
    if (!setup_error_.ok()) return;
    loop();
    shutdown_all();
}

void Worker::arm_accept() noexcept {
    // Direct: the kernel picks a free slot, and -ENFILE when the table is full (handled like
    // running out of descriptors).
    loop_.accept(listen_fd_, net::encode_user_data(Op::Accept, 0, 0), multishot_accept_);
}

void Worker::arm_stop() noexcept {
    loop_.read(stop_fd_, &stop_value_, sizeof stop_value_, net::encode_user_data(Op::Stop, 0, 0));
}

void Worker::arm_mail() noexcept {
    loop_.read(mail_fd_, &mail_value_, sizeof mail_value_, net::encode_user_data(Op::Mail, 0, 0));
}

void Worker::request_eviction() noexcept {
    evict_requests_.fetch_add(1, std::memory_order_relaxed);
    std::uint64_t one = 1;
    [[maybe_unused]] auto n = ::write(mail_fd_, &one, sizeof one);
}

std::uint32_t Worker::eviction_victim() const noexcept {
    // A TLS connection still in its handshake has not shown who it is: it goes before any
    // authenticated session, oldest first.
    if (handshaking_ > 0)
        for (std::uint32_t i = lru_head_; i != kNoConn; i = conns_[i].lru_next)
            if (conns_[i].link.setting_up()) return i;
    return lru_head_;
}

void Worker::serve_evictions() noexcept {
    // Each request closes this worker's oldest idle connection, if it still has one (it may
    // have closed meanwhile: then the server is below the limit anyway).
    for (std::uint32_t n = evict_requests_.exchange(0, std::memory_order_relaxed); n > 0; --n) {
        if (lru_head_ == kNoConn) break;
        counters_.add(ServerCounters::Evictions);
        close_connection(eviction_victim());
    }
}

void Worker::publish_oldest_idle() noexcept {
    if (!cross_evict_) return;
    oldest_idle_ns_.store(lru_head_ == kNoConn ? INT64_MAX : conns_[lru_head_].last_active_ns,
                          std::memory_order_relaxed);
}

bool Worker::evict_server_wide_oldest() noexcept {
    if (handshaking_ > 0) {  // this worker's unauthenticated connections go first
        counters_.add(ServerCounters::Evictions);
        close_connection(eviction_victim());
        return true;
    }
    Worker* victim = nullptr;
    std::int64_t oldest = INT64_MAX;
    if (lru_head_ != kNoConn) {
        victim = this;
        oldest = conns_[lru_head_].last_active_ns;
    }
    for (Worker* peer : peers_) {
        if (peer == this) continue;
        const std::int64_t t = peer->oldest_idle_ns_.load(std::memory_order_relaxed);
        if (t < oldest) {
            oldest = t;
            victim = peer;
        }
    }
    if (victim == nullptr) return false;
    if (victim == this) {
        counters_.add(ServerCounters::Evictions);
        close_connection(eviction_victim());
    } else {
        // The new connection is admitted now; the server is one over its limit until the
        // other worker has closed its oldest (it counts the eviction).
        victim->request_eviction();
    }
    return true;
}

void Worker::arm_recv(std::uint32_t index) noexcept {
    Connection& c = conns_[index];
    const std::uint64_t data = net::encode_user_data(Op::Recv, index, c.generation);
    const bool armed = use_buf_ring_
                           ? loop_.recv(c.fd, data, multishot_recv_)
                           : loop_.recv_into(c.fd, c.plain_buf.get(), config_.buf_size, data);
    if (armed) c.recv_armed = true;
}

void Worker::cancel_recv(std::uint32_t index) noexcept {
    Connection& c = conns_[index];
    loop_.cancel_input(c.fd, net::encode_user_data(Op::Recv, index, c.generation),
                       net::encode_user_data(Op::Cancel, index, c.generation));
}

void Worker::loop() noexcept {
    while (!stopping_) {
        std::int64_t deadline = next_deadline();
        std::int64_t wait = deadline < 0 ? -1 : std::max<std::int64_t>(deadline - now_, 0);
        int rc = loop_.submit_and_wait(1, wait);
        if (net::wait_failed(rc)) break;
        now_ = net::now_ns();
        loop_.drain([this](const net::Completion& cqe) { on_cqe(cqe); });
        for (std::uint32_t index : rearm_) {
            Connection& c = conns_[index];
            if (c.state == Connection::State::Open && !c.recv_armed && !c.paused) arm_recv(index);
        }
        rearm_.clear();
        run_timers();
        // One send per connection for everything that arrived in this batch.
        dirty_.drain([this](std::uint32_t index) {
            conns_[index].dirty = false;
            flush(index);
        });
    }
}

void Worker::shutdown_all() noexcept {
    // Close the listener and every connection, then let the kernel finish what is in flight
    // (sends read our blocks) before the ring and the pool go away.
    ::shutdown(listen_fd_, SHUT_RDWR);
    for (std::uint32_t i = 0; i < conns_.size(); ++i) close_connection(i);
    loop_.cancel_all(net::encode_user_data(Op::Cancel, 0, 0));
    std::int64_t until = net::now_ns() + kStopDrainNs;
    auto busy = [this] {
        for (std::uint32_t i = 0; i < conns_.size(); ++i)
            if (conns_[i].state == Connection::State::Closing) return true;
        return false;
    };
    while (busy() && net::now_ns() < until) {
        loop_.submit_and_wait(1, 50 * net::kNsPerMs);
        loop_.drain([this](const net::Completion& cqe) { on_cqe(cqe); });
    }
}

void Worker::on_cqe(const net::Completion& cqe) noexcept {
    switch (static_cast<Op>(net::decode_user_data(cqe.user_data).op)) {
        case Op::Accept:
            on_accept(cqe);
            break;
        case Op::Recv:
            on_recv(cqe);
            break;
        case Op::Send:
            on_send(cqe);
            break;
        case Op::Stop:
            stopping_ = true;
            break;
        case Op::AcceptPause:
            if (!stopping_) arm_accept();
            break;
        case Op::Mail:
            serve_evictions();
            if (!stopping_) arm_mail();
            break;
        case Op::Cancel:
        case Op::SocketShutdown:
        case Op::SocketClose:
            break;  // the cancelled recv reports itself; a closed slot is free for accepts
    }
}

void Worker::on_accept(const net::Completion& cqe) noexcept {
    if (cqe.res >= 0) {
        if (stopping_)
            close_socket(cqe.res);
        else
            admit(cqe.res);
    }
    const bool out_of_fds = cqe.res == -EMFILE || cqe.res == -ENFILE;
    if (out_of_fds)
        counters_.add(ServerCounters::AcceptFdExhausted);
    else if (cqe.res >= 0)
        accept_pause_ns_ = kAcceptPauseMinNs;
    const bool more = (cqe.flags & IORING_CQE_F_MORE) != 0;
    if (more || stopping_ || cqe.res == -EBADF || cqe.res == -EINVAL) return;
    if (out_of_fds)
        pause_accept();
    else
        arm_accept();
}

void Worker::pause_accept() noexcept {
    // Read by the kernel when the SQE is submitted; a member, so it outlives that.
    accept_pause_ts_.tv_sec = accept_pause_ns_ / net::kNsPerSec;
    accept_pause_ts_.tv_nsec = accept_pause_ns_ % net::kNsPerSec;
    if (!loop_.timeout(&accept_pause_ts_, net::encode_user_data(Op::AcceptPause, 0, 0))) return;
    accept_pause_ns_ = std::min(accept_pause_ns_ * 2, kAcceptPauseMaxNs);
}

void Worker::admit(int fd) noexcept {
    const std::uint32_t limit = config_.max_connections;
    bool evict_when_established = false;
    if (limit != 0 && open_connections_.load(std::memory_order_relaxed) >= limit) {
        const bool evict = config_.full_policy == FullPolicy::EvictOldestIdle;
        // Every connection held has authenticated and the newcomer has not: it may not push
        // one out before it has shown who it is (one over the limit until then; a socket that
        // never does is closed by its frame timeout, or evicted by the next newcomer).
        evict_when_established = evict && config_.tls && handshaking_ == 0;
        const bool evicted = evict && !evict_when_established &&
                             (cross_evict_ ? evict_server_wide_oldest() : lru_head_ != kNoConn);
        if (evicted && !cross_evict_) {
            counters_.add(ServerCounters::Evictions);
            close_connection(eviction_victim());
        } else if (!evicted && !evict_when_established) {
            counters_.add(ServerCounters::Refusals);
            close_socket(fd);
            return;
        }
    }
    std::uint32_t index;
    try {
        if (!free_slots_.empty()) {
            index = free_slots_.back();
            free_slots_.pop_back();
        } else {
            conns_.emplace_back();
            index = static_cast<std::uint32_t>(conns_.size() - 1);
        }
        Connection& c = conns_[index];
        if (!use_buf_ring_ && !c.plain_buf) c.plain_buf.reset(new std::uint8_t[config_.buf_size]);
    } catch (...) {
        counters_.add(ServerCounters::Refusals);
        close_socket(fd);
        return;
    }
    Connection& c = conns_[index];
    // Direct sockets have these from the listener (accepted sockets inherit them).
    if (!direct_) {
        net::set_nodelay(fd);
        if (config_.socket_send_buffer > 0)
            setsockopt(fd, SOL_SOCKET, SO_SNDBUF, &config_.socket_send_buffer,
                       sizeof config_.socket_send_buffer);
    }
    c.fd = fd;
    c.state = Connection::State::Open;
    c.recv_armed = c.send_inflight = c.paused = c.dirty = false;
    c.peer_done = c.framing_lost = false;
    c.frame_started_ns = 0;
    c.hold_pos = kNoHold;
    c.unanswered = 0;
    c.evict_when_set_up = evict_when_established;
    if (!c.link.accepted(link_kind_, config_.tls, &config_.tls_roles, ktls_)) {
        c.state = Connection::State::Free;  // no TLS session could be made
        free_slots_.push_back(index);
        counters_.add(ServerCounters::Refusals);
        close_socket(fd);
        return;
    }
    c.last_active_ns = now_ ? now_ : net::now_ns();
    if (c.link.setting_up()) {
        // The handshake is timed from the accept: a socket that never sends a byte holds a
        // TLS slot as surely as one that stops half-way.
        ++handshaking_;
        start_frame_clock(c, index);
        c.frame_started_ns = c.last_active_ns;
    }
    lru_push_back(index);
    ++open_here_;
    open_connections_.fetch_add(1, std::memory_order_relaxed);
    counters_.add(ServerCounters::ConnectionsCurrent);
    counters_.add(ServerCounters::ConnectionsTotal);
    arm_recv(index);
}

void Worker::close_connection(std::uint32_t index) noexcept {
    Connection& c = conns_[index];
    if (c.state != Connection::State::Open) return;
    c.state = Connection::State::Closing;
    if (c.link.setting_up()) --handshaking_;
    lru_unlink(index);
    // shutdown() ends a pending recv/send at once; the ops still hold the socket, so the
    // descriptor can be closed now and the slot released when they have completed.
    if (direct_) {
        close_socket(c.fd);  // shutdown, then close, in the kernel's order
    } else {
        ::shutdown(c.fd, SHUT_RDWR);
    }
    if (c.recv_armed) cancel_recv(index);
    drop_stash(index);
    if (!direct_) loop_.close(c.fd);  // epoll: its pending send ends now
    c.fd = -1;
    --open_here_;
    open_connections_.fetch_sub(1, std::memory_order_relaxed);
    counters_.sub(ServerCounters::ConnectionsCurrent);
    maybe_release(index);
}

void Worker::close_socket(int fd) noexcept {
    if (!direct_) {
        loop_.close(fd);
        return;
    }
    const auto slot = static_cast<std::uint32_t>(fd);
    loop_.shutdown_and_close_slot(slot, net::encode_user_data(Op::SocketShutdown, slot, 0),
                                  net::encode_user_data(Op::SocketClose, slot, 0));
}

void Worker::maybe_release(std::uint32_t index) noexcept {
    Connection& c = conns_[index];
    if (c.state != Connection::State::Closing || c.recv_armed || c.send_inflight) return;
    counters_.sub(ServerCounters::PendingOutput, c.out.bytes());
    c.out.clear(pool_);
    c.link.released();
    c.hold_pos = kNoHold;
    c.frame_started_ns = 0;
    c.state = Connection::State::Free;
    c.generation = net::next_generation(c.generation);
    free_slots_.push_back(index);  // capacity reserved; grows only past the expected maximum
}

void Worker::on_recv(const net::Completion& cqe) noexcept {
    const net::UserData ud = net::decode_user_data(cqe.user_data);
    if (ud.index >= conns_.size()) return;
    Connection& c = conns_[ud.index];
    const bool has_buffer = use_buf_ring_ && net::BufRing::has_buffer(cqe.flags);
    const std::uint16_t bid = has_buffer ? net::BufRing::buffer_id(cqe.flags) : 0;
    if (c.generation != ud.generation || c.state == Connection::State::Free) {
        if (has_buffer) loop_.recycle(bid);
        return;
    }
    if (!(cqe.flags & IORING_CQE_F_MORE)) c.recv_armed = false;

    bool keep_buffer = false;
    if (c.state == Connection::State::Open) {
        if (cqe.res > 0 && c.framing_lost) {
            // Read and dropped (not left unread, which would turn the close into a reset that
            // could destroy the answers still in flight); not activity either.
            counters_.add(ServerCounters::BytesIn, static_cast<std::uint64_t>(cqe.res));
        } else if (cqe.res > 0) {
            counters_.add(ServerCounters::BytesIn, static_cast<std::uint64_t>(cqe.res));
            touch(ud.index);
            if (has_buffer && (c.paused || c.stash_head != kNoBuffer)) {
                stash(ud.index, bid, static_cast<std::uint32_t>(cqe.res));
                keep_buffer = true;
            } else {
                const std::uint8_t* data = has_buffer ? loop_.buffer(bid) : c.plain_buf.get();
                consume_input(ud.index, data, static_cast<std::size_t>(cqe.res));
            }
        } else if (cqe.res == 0) {
            // The peer half-closed (or closed): what it sent before is still answered.
            c.peer_done = true;
            c.frame_started_ns = 0;  // a partial frame can no longer complete: not timed
            if (c.recv_armed) cancel_recv(ud.index);
        } else if (c.link.is_record_layer_error(cqe.res)) {
            // The kernel's TLS passes no record but data (close_notify, an alert, a TLS 1.3
            // KeyUpdate it cannot follow): the input ends there, counted; answers still go.
            counters_.add(ServerCounters::TlsOffloadErrors);
            c.peer_done = true;
            c.frame_started_ns = 0;
        } else if (cqe.res != -ENOBUFS && cqe.res != -ECANCELED && cqe.res != -EINTR) {
            close_connection(ud.index);
        }
    }
    if (has_buffer && !keep_buffer) loop_.recycle(bid);

    if (c.state == Connection::State::Open && !c.peer_done && !check_backpressure(ud.index) &&
        !c.recv_armed) {
        if (cqe.res == -ENOBUFS)
            rearm_.push_back(ud.index);  // after this batch has returned its buffers
        else
            arm_recv(ud.index);
    }
    close_if_answered(ud.index);
    maybe_release(ud.index);
}

void Worker::close_if_answered(std::uint32_t index) noexcept {
    Connection& c = conns_[index];
    if (c.state != Connection::State::Open || !(c.peer_done || c.framing_lost)) return;
    if (c.out.empty() && c.stash_head == kNoBuffer && !c.link.has_own_output())
        close_connection(index);
}

void Worker::lose_framing(std::uint32_t index, bool crc) noexcept {
    Connection& c = conns_[index];
    counters_.add(crc ? ServerCounters::CrcErrors : ServerCounters::BadFramingCloses);
    c.framing_lost = true;
    c.frame_started_ns = 0;
    drop_stash(index);
}

bool Worker::check_backpressure(std::uint32_t index) noexcept {
    Connection& c = conns_[index];
    if (c.paused) return true;
    if (c.out.bytes() <= config_.max_pending_output) return false;
    // A client that does not read stops being read.
    c.paused = true;
    counters_.add(ServerCounters::BackpressurePauses);
    if (c.recv_armed && multishot_recv_) cancel_recv(index);
    return true;
}

void Worker::stash(std::uint32_t index, std::uint16_t bid, std::uint32_t size) noexcept {
    Connection& c = conns_[index];
    stash_next_[bid] = kNoBuffer;
    stash_size_[bid] = size;
    if (c.stash_tail == kNoBuffer)
        c.stash_head = bid;
    else
        stash_next_[c.stash_tail] = bid;
    c.stash_tail = bid;
}

void Worker::drain_stash(std::uint32_t index) noexcept {
    Connection& c = conns_[index];
    while (c.stash_head != kNoBuffer && c.state == Connection::State::Open && !c.paused &&
           !c.framing_lost) {
        const std::uint16_t bid = c.stash_head;
        c.stash_head = stash_next_[bid];
        if (c.stash_head == kNoBuffer) c.stash_tail = kNoBuffer;
        consume_input(index, loop_.buffer(bid), stash_size_[bid]);
        loop_.recycle(bid);
        if (c.state == Connection::State::Open) check_backpressure(index);
    }
}

void Worker::drop_stash(std::uint32_t index) noexcept {
    Connection& c = conns_[index];
    while (c.stash_head != kNoBuffer) {
        const std::uint16_t bid = c.stash_head;
        c.stash_head = stash_next_[bid];
        loop_.recycle(bid);
    }
    c.stash_tail = kNoBuffer;
}

void Worker::consume_input(std::uint32_t index, const std::uint8_t* data,
                           std::size_t size) noexcept {
    Connection& c = conns_[index];
    bool set_up = false;
    LinkInput got = c.link.take(codec::Bytes(data, size), link_scratch_, set_up);
    if (set_up) on_link_set_up(index);  // before the requests after it
    bool completed = false;
    if (got == LinkInput::Drained) [[likely]] {
        codec::TcpFrame frame;
        std::uint64_t discarded = 0;
        std::uint64_t crc_skipped = 0;
        while (c.link.next_request(frame, got, discarded, crc_skipped)) {
            // Nothing of the link may be touched after a close: the slot may be free.
            if (!on_frame(c, index, frame)) {
                got = LinkInput::Stopped;
                break;
            }
            completed = true;
        }
        count_dropped_frames(discarded, crc_skipped);
        completed = completed || discarded != 0;
    }
    if (got == LinkInput::Stopped) {  // closed while serving: the slot may be free already
        flush_tally();
        return;
    }
    // One dirty mark per input, not per frame (7 instructions a frame).
    if (completed) mark_dirty(c, index);
    flush_tally();
    if (got == LinkInput::Drained) [[likely]] {
        counters_.set_max(ServerCounters::PendingOutputPeak, c.out.bytes());
        note_partial_frame(c, index, completed);
    } else if (!on_link_event(index, got)) {
        return;
    }
    if (c.link.may_need_care()) after_link_input(index);
}

void Worker::note_partial_frame(Connection& c, std::uint32_t index, bool completed) noexcept {
    if (c.link.buffered() == 0) {
        c.frame_started_ns = 0;
        return;
    }
    if (c.frame_started_ns != 0 && !completed) return;  // the same frame, still arriving
    start_frame_clock(c, index);
}

void Worker::start_frame_clock(Connection& c, std::uint32_t index) noexcept {
    c.frame_started_ns = now_;
    if (config_.frame_timeout_ms != 0 && !c.in_partial_list) {
        c.in_partial_list = true;
        partial_.push_back(index);
    }
}

void Worker::flush_reads() noexcept {
    // [1]: FC03 (holding registers), [0]: FC04 (input registers).
    const std::uint64_t holding = tally_.reads_by_function[1];
    const std::uint64_t input = tally_.reads_by_function[0];
    if (holding + input == 0) return;
    counters_.add_request(static_cast<std::uint8_t>(codec::FunctionCode::ReadHoldingRegisters),
                          holding);
    counters_.add_request(static_cast<std::uint8_t>(codec::FunctionCode::ReadInputRegisters),
                          input);
    if (model_.track_diagnostics())
        model_.diagnostics().note_messages(holding + input, slave::kReceiveEvent,
                                           slave::kSendEvent);
    tally_.reads_by_function[0] = tally_.reads_by_function[1] = 0;
}

void Worker::flush_tally() noexcept {
    flush_reads();
    counters_.add(ServerCounters::Requests, tally_.requests);
    counters_.add(ServerCounters::Transactions, tally_.transactions);
    counters_.add(ServerCounters::PendingOutput, tally_.pending_output);
    tally_ = {};
}

bool Worker::on_frame(Connection& c, std::uint32_t index, const codec::TcpFrame& frame) noexcept {
    ++tally_.requests;
    // The load test's request on a plain server: an FC03/04 answered inline, with none of the
    // checks below configured (plain_frames_: RTU framing among them) or owed to this
    // connection (TLS roles).
    if (plain_frames_ && c.link.allowed() == nullptr) [[likely]] {
        std::uint8_t* p;
        try {
            // The slack: the shortcut copies whole words past the answer's end.
            p = c.out.reserve(pool_, codec::limits::kMaxTcpAdu + slave::kReadSlack);
        } catch (...) {
            p = nullptr;  // the general path below tries again and closes
        }
        if (p) {
            slave::HandleResult r;
            // Its copy may overwrite the 6 bytes before the PDU: the MBAP header, written after.
            static_assert(codec::limits::kMbapHeader >= slave::kReadSlack);
            if (slave::read_registers_uncounted(frame.pdu, model_, p + codec::limits::kMbapHeader,
                                                r)) {
                ++tally_.reads_by_function[r.function & 1];
                codec::write_mbap_header(p, frame.header.transaction_id, frame.header.unit_id,
                                         r.size);
                const std::size_t n = codec::limits::kMbapHeader + r.size;
                c.out.commit(n);
                tally_.pending_output += n;
                ++tally_.transactions;
                ++c.unanswered;
                return true;
            }
        }
    }
    if (!frame.pdu.empty()) counters_.add_request(frame.pdu[0]);
    if (const FunctionSet* allowed = c.link.allowed();
        allowed != nullptr && !frame.pdu.empty() && !allowed->test(frame.pdu[0])) {
        counters_.add(ServerCounters::TlsRoleDenied);
        queue_exception(c, frame, codec::ExceptionCode::IllegalFunction);
        return true;
    }
    if (config_.only_unit && frame.header.unit_id != *config_.only_unit) {
        counters_.add(ServerCounters::ForeignUnit);
        if (config_.foreign_unit == ForeignUnitPolicy::GatewayException)
            queue_exception(c, frame, codec::ExceptionCode::GatewayTargetFailedToRespond);
        return true;
    }
    if (config_.max_outstanding != 0 && c.unanswered >= config_.max_outstanding) {
        counters_.add(ServerCounters::BusyRejects);
        queue_exception(c, frame, codec::ExceptionCode::ServerDeviceBusy);
        return true;
    }

    slave::FaultDecision decision;
    std::int64_t release_ns = 0;
    if (faults_.enabled()) {
        decision = faults_.decide();
        if (decision.action == slave::FaultDecision::Action::Drop) {
            counters_.add(ServerCounters::FaultDrops);
            flush_tally();  // before the close takes the connection's output off PendingOutput
            close_connection(index);
            return false;
        }
        if (decision.action == slave::FaultDecision::Action::NoAnswer) {
            counters_.add(ServerCounters::FaultNoAnswer);
            return true;
        }
        const std::uint64_t due = static_cast<std::uint64_t>(now_) + decision.delay_ns;
        release_ns = static_cast<std::int64_t>(faults_.held_until(due));
        if (release_ns > now_) {
            counters_.add(ServerCounters::FaultDelayed);
            hold_from_here(index, release_ns);
        }
        if (decision.action == slave::FaultDecision::Action::Exception) {
            queue_exception(c, frame, decision.exception);
            return true;
        }
    }

    std::uint8_t* p;
    try {
        p = c.out.reserve(pool_, codec::limits::kMaxTcpAdu);
    } catch (...) {
        flush_tally();
        close_connection(index);
        return false;
    }
    const codec::MutableBytes pdu_out(p + c.link.answer_offset(), slave::kMinOutput);
    slave::HandleResult r;
    flush_reads();  // this request's diagnostics come after the reads before it
    if (units_ || !slave::read_registers_inline(frame.pdu, model_, pdu_out.data(), r)) {
        r = units_ ? slave::handle_request(frame.header.unit_id, frame.pdu, *units_, pdu_out)
                   : slave::handle_request(frame.pdu, model_, pdu_out);
    }
    if (r.outcome == slave::Outcome::NoResponse || r.size == 0) return true;
    const std::size_t n = c.link.frame_answer(p, frame, r.size);
    c.out.commit(n);
    tally_.pending_output += n;
    ++tally_.transactions;
    if (r.outcome == slave::Outcome::Exception)
        counters_.add_exception(static_cast<std::uint8_t>(r.exception));
    ++c.unanswered;
    return true;
}

void Worker::queue_exception(Connection& c, const codec::TcpFrame& frame,
                             codec::ExceptionCode code) noexcept {
    std::uint8_t* p;
    try {
        p = c.out.reserve(pool_, Link::kMaxExceptionSize);
    } catch (...) {
        return;
    }
    const std::size_t n = c.link.write_exception(p, frame, code);
    c.out.commit(n);
    tally_.pending_output += n;
    ++tally_.transactions;
    counters_.add_exception(static_cast<std::uint8_t>(code));
}

void Worker::hold_from_here(std::uint32_t index, std::int64_t until_ns) noexcept {
    Connection& c = conns_[index];
    // One hold per connection: later delayed responses extend it, so order is kept (an
    // earlier response may then wait a little longer than its own delay).
    if (c.hold_pos == kNoHold) {
        c.hold_pos = c.out.written_position();
        c.hold_until_ns = until_ns;
    } else {
        c.hold_until_ns = std::max(c.hold_until_ns, until_ns);
    }
    if (!c.in_hold_list) {
        c.in_hold_list = true;
        held_.push_back(index);
    }
}

void Worker::mark_dirty(Connection& c, std::uint32_t index) noexcept {
    dirty_.mark(c.dirty, index);
}

void Worker::flush(std::uint32_t index) noexcept {
    Connection& c = conns_[index];
    if (c.state != Connection::State::Open || c.send_inflight) return;
    std::size_t size = 0;
    const std::uint8_t* p = c.out.sendable(c.hold_pos, size);
    codec::Bytes wire;
    if (!c.link.outgoing(p, size, wire)) {
        close_connection(index);
        return;
    }
    if (wire.empty()) return;
    if (!loop_.send(c.fd, wire.data(), static_cast<unsigned>(wire.size()),
                    net::encode_user_data(Op::Send, index, c.generation)))
        return;
    c.send_inflight = true;
}

void Worker::on_send(const net::Completion& cqe) noexcept {
    const net::UserData ud = net::decode_user_data(cqe.user_data);
    if (ud.index >= conns_.size()) return;
    Connection& c = conns_[ud.index];
    if (c.generation != ud.generation || !c.send_inflight) return;
    c.send_inflight = false;
    if (c.state != Connection::State::Open) {
        maybe_release(ud.index);
        return;
    }
    if (cqe.res < 0) {
        close_connection(ud.index);
        return;
    }
    counters_.add(ServerCounters::BytesOut, static_cast<std::uint64_t>(cqe.res));
    const std::size_t n = c.link.sent(static_cast<std::size_t>(cqe.res));
    counters_.sub(ServerCounters::PendingOutput, n);
    if (n != 0) c.out.consume(pool_, n);  // TLS: 0 until a record carrying output is sent
    if (c.out.empty()) c.unanswered = 0;
    if (c.paused && c.out.bytes() <= config_.max_pending_output / 2) {
        c.paused = false;
        if (c.frame_started_ns != 0) c.frame_started_ns = now_;  // the pause does not count
        drain_stash(ud.index);
        if (c.state != Connection::State::Open) return;
        if (!c.paused && !c.recv_armed && !c.peer_done) arm_recv(ud.index);
    }
    flush(ud.index);
    close_if_answered(ud.index);
}

void Worker::run_timers() noexcept {
    if (!held_.empty()) {
        std::size_t keep = 0;
        for (std::size_t i = 0; i < held_.size(); ++i) {
            const std::uint32_t index = held_[i];
            Connection& c = conns_[index];
            if (c.state != Connection::State::Open || c.hold_pos == kNoHold) {
                c.in_hold_list = false;
                c.hold_pos = kNoHold;
                continue;
            }
            if (c.hold_until_ns <= now_) {
                c.hold_pos = kNoHold;
                c.in_hold_list = false;
                mark_dirty(c, index);
                continue;
            }
            held_[keep++] = index;
        }
        held_.resize(keep);
    }
    if (!partial_.empty()) {
        const std::int64_t timeout =
            static_cast<std::int64_t>(config_.frame_timeout_ms) * net::kNsPerMs;
        std::size_t keep = 0;
        for (std::size_t i = 0; i < partial_.size(); ++i) {
            const std::uint32_t index = partial_[i];
            Connection& c = conns_[index];
            if (c.state != Connection::State::Open || c.frame_started_ns == 0) {
                c.in_partial_list = false;
                continue;
            }
            // Paused, the rest of the frame may wait in the stash for us, not for the client.
            if (!c.paused && now_ - c.frame_started_ns >= timeout) {
                c.in_partial_list = false;
                counters_.add(ServerCounters::FrameTimeouts);
                close_connection(index);
                continue;
            }
            partial_[keep++] = index;
        }
        partial_.resize(keep);
    }
    if (config_.idle_timeout_ms != 0) {
        const std::int64_t timeout =
            static_cast<std::int64_t>(config_.idle_timeout_ms) * net::kNsPerMs;
        while (lru_head_ != kNoConn && now_ - conns_[lru_head_].last_active_ns >= timeout) {
            counters_.add(ServerCounters::IdleCloses);
            close_connection(lru_head_);
        }
    }
    trim_output_blocks();
    counters_.set_max(ServerCounters::OutputBlocks, pool_.allocated());
    counters_.set(ServerCounters::OutputBlocksHeld, pool_.allocated());
}

// A crowd of slow readers may have needed thousands of blocks (140 MB stayed after 1,500
// non-reading clients left, issue #31): those no get() took for a whole interval are freed,
// keeping the prewarmed ones and 1 MiB of slack, so that a steady load never allocates again.
std::size_t Worker::blocks_kept() const noexcept {
    constexpr std::size_t kSlackBlocks = 64;
    return config_.prealloc_output_blocks + kSlackBlocks;
}

void Worker::trim_output_blocks() noexcept {
    constexpr std::int64_t kTrimIntervalNs = net::kNsPerSec;
    if (now_ < next_trim_ns_) return;
    next_trim_ns_ = now_ + kTrimIntervalNs;
    // glibc keeps freed 16 KB chunks in its arenas: malloc_trim hands their pages to the
    // kernel, so that the process's resident memory falls too.
    if (pool_.trim(blocks_kept()) != 0) ::malloc_trim(0);
}

std::int64_t Worker::next_deadline() const noexcept {
    std::int64_t deadline = -1;
    for (std::uint32_t index : held_) {
        const Connection& c = conns_[index];
        if (c.hold_pos != kNoHold && (deadline < 0 || c.hold_until_ns < deadline))
            deadline = c.hold_until_ns;
    }
    for (std::uint32_t index : partial_) {
        const Connection& c = conns_[index];
        if (c.state != Connection::State::Open || c.frame_started_ns == 0 || c.paused) continue;
        const std::int64_t due =
            c.frame_started_ns +
            static_cast<std::int64_t>(config_.frame_timeout_ms) * net::kNsPerMs;
        if (deadline < 0 || due < deadline) deadline = due;
    }
    if (config_.idle_timeout_ms != 0 && lru_head_ != kNoConn) {
        const std::int64_t idle =
            conns_[lru_head_].last_active_ns +
            static_cast<std::int64_t>(config_.idle_timeout_ms) * net::kNsPerMs;
        if (deadline < 0 || idle < deadline) deadline = idle;
    }
    // Blocks above what is kept: wake to give the idle ones back, even with nothing else due.
    if (pool_.above(blocks_kept()) && (deadline < 0 || next_trim_ns_ < deadline))
        deadline = next_trim_ns_;
    return deadline;
}

void Worker::lru_unlink(std::uint32_t index) noexcept {
    Connection& c = conns_[index];
    if (c.lru_prev != kNoConn)
        conns_[c.lru_prev].lru_next = c.lru_next;
    else if (lru_head_ == index)
        lru_head_ = c.lru_next;
    if (c.lru_next != kNoConn)
        conns_[c.lru_next].lru_prev = c.lru_prev;
    else if (lru_tail_ == index)
        lru_tail_ = c.lru_prev;
    c.lru_prev = c.lru_next = kNoConn;
    publish_oldest_idle();
}

void Worker::lru_push_back(std::uint32_t index) noexcept {
    Connection& c = conns_[index];
    c.lru_prev = lru_tail_;
    c.lru_next = kNoConn;
    if (lru_tail_ != kNoConn)
        conns_[lru_tail_].lru_next = index;
    else
        lru_head_ = index;
    lru_tail_ = index;
    publish_oldest_idle();
}

void Worker::touch(std::uint32_t index) noexcept {
    Connection& c = conns_[index];
    c.last_active_ns = now_;
    if (lru_tail_ != index) {
        lru_unlink(index);
        lru_push_back(index);
    } else if (lru_head_ == index) {
        publish_oldest_idle();  // the only connection: still the oldest, now less idle
    }
}

}  // namespace mbstorm::server
