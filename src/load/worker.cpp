#include "load/worker.hpp"

#include <fmt/format.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <functional>
#include <system_error>

#include "load/response_check.hpp"
#include "load/result_rows.hpp"
#include "load/rng.hpp"
#include "load/thread_share.hpp"
#include "net/clock.hpp"
#include "net/direct_socket.hpp"
#include "net/features.hpp"
#include "net/kernel_tls.hpp"
#include "net/user_data.hpp"

namespace mbstorm::load {
namespace {

constexpr std::int64_t kMaxSleepNs = 20 * net::kNsPerMs;
// Ramps move the rate and the connection count this often: smooth enough, cheap enough.
constexpr std::int64_t kStageUpdateNs = 10 * net::kNsPerMs;
constexpr std::uint16_t kBufferGroup = 0;
// Up to this many operations, each answer's latency is recorded once, into its operation's
// interval histogram (about 270 KB each, per worker); more operations record it twice (into
// the operation's run-long histogram and the interval's) rather than hold that many more.
constexpr std::size_t kMaxOperationsRecordedOnce = 16;

std::uint32_t recorder_tags(std::size_t operations, std::uint32_t timeline_tags) noexcept {
    if (operations > 1 && operations <= kMaxOperationsRecordedOnce)
        return std::max(timeline_tags, static_cast<std::uint32_t>(operations));
    return timeline_tags;
}

bool has_response(stats::Outcome o) noexcept {
    return o != stats::Outcome::Timeout && o != stats::Outcome::ConnectionClosed &&
           o != stats::Outcome::ConnectFailed && o != stats::Outcome::FramingError &&
           o != stats::Outcome::CrcError;
}

// Ports of the range tried in turn when a connection's own is taken (bind_source).
constexpr std::uint32_t kPortProbes = 16;

using HeapEntry = std::pair<std::int64_t, std::uint32_t>;
constexpr auto kHeapOrder = std::greater<HeapEntry>{};  // min-heap on the due time

}  // namespace

Worker::Worker(WorkerSetup setup)
    : setup_(std::move(setup)),
      plan_(*setup_.plan),
      open_loop_(plan_.model == LoadModel::OpenLoop),
      quota_(setup_.quota),
      generator_(plan_.operations, derive_seed(plan_.seed, setup_.index)),
      lag_(plan_.late_threshold.count()),
      interval_(setup_.timeline->interval_ns(), stats::Histogram::kOneHourNs,
                recorder_tags(plan_.operations.size(), setup_.timeline->tags())) {
    operations = operation_rows(plan_.operations);
    if (setup_.schedule != nullptr) stages = stage_rows(setup_.schedule->stages(), operations);
    // An operation's run-long histogram is the sum of the intervals' histograms of it, folded
    // in as each interval ends, so an answer's latency is recorded once instead of twice.
    if (operations.size() == 1) {
        interval_.fold_into(&operations.front().latency);
    } else if (operations.size() <= kMaxOperationsRecordedOnce) {
        std::vector<stats::Histogram*> totals;
        for (stats::OperationResult& op : operations) totals.push_back(&op.latency);
        interval_.fold_tags_into(std::move(totals));
        latency_by_operation_ = true;
    }
    rate_ = setup_.rate;
    active_ = setup_.connections;
    const auto half = static_cast<std::uint32_t>(plan_.depth * max_request_size(plan_.operations));
    connections_.reserve(setup_.connections);
    // The transport is chosen here, once: each connection's link knows it from now on.
    const Link::Kind kind = plan_.tls                              ? Link::Kind::Tls
                            : plan_.framing == codec::Framing::Rtu ? Link::Kind::Rtu
                                                                   : Link::Kind::Mbap;
    for (std::uint32_t i = 0; i < setup_.connections; ++i) {
        connections_.emplace_back(plan_.depth, half, std::uint16_t{0},
                                  Link(kind, plan_.tls, plan_.tls_resume));
        connections_.back().backoff_ns = plan_.reconnect_backoff_min.count();
    }
    // A recv's plaintext is at most its ciphertext plus one record the session held back.
    if (kind == Link::Kind::Tls) link_scratch_.resize(16384 + 17 * 1024);
    dirty_.reserve(setup_.connections);
    ready_.assign(setup_.connections, 0);
    connect_heap_.reserve(setup_.connections);
    connect_interval_ns_ = static_cast<std::int64_t>(1e9 / std::max(setup_.connect_rate, 1e-3));
    sweep_interval_ns_ = std::clamp<std::int64_t>(plan_.transaction_timeout.count() / 10,
                                                  net::kNsPerMs, 100 * net::kNsPerMs);
    std::int64_t sec = 0;
    long long nsec = 0;
    net::ns_to_timespec(plan_.connect_timeout.count(), sec, nsec);
    connect_timeout_ts_.tv_sec = sec;
    connect_timeout_ts_.tv_nsec = nsec;
}

void Worker::run() noexcept {
    if (setup_io()) {
        if (setup_.schedule != nullptr) {
            // Warm-up runs at the first stage's start values.
            const StageTargets t = setup_.schedule->at(-1);
            active_ = share_of(t.connections);
            rate_ = t.connections == 0 ? 0 : t.rate * active_ / t.connections;
            next_stage_update_ns_ = setup_.measure_start_ns;
        }
        for (std::uint32_t i = 0; i < active_; ++i) queue_connect(i, setup_.connect_start_ns);
        next_connect_allowed_ns_ = setup_.connect_start_ns;
        next_sweep_ns_ = setup_.connect_start_ns + sweep_interval_ns_;
        loop();
        teardown();
    } else {
        setup_.abort->store(true);
    }
    schedule_lag = lag_.lag();
    if (finished_ns == 0) finished_ns = net::now_ns();
}

bool Worker::setup_io() noexcept {
    // The engine chose the backend (net::choose_backend): io_uring has buffer rings here.
    const bool uring = setup_.backend == net::Backend::IoUring;
    multishot_ = !uring || net::features().multishot_recv;
    direct_ = uring && setup_.direct_descriptors;
    // The kernel's TLS needs a hand-off with no recv in flight (single-shot recvs) and a
    // socket setsockopt can reach (the engine gives no direct descriptors then).
    ktls_ = plan_.tls && net::kernel_tls().available;
    if (ktls_) multishot_ = false;
    net::RingOptions options;
    options.entries = std::clamp<unsigned>(std::bit_ceil(2 * setup_.connections + 16), 64, 4096);
    if (Error e = loop_.init(setup_.backend, options); !e.ok()) {
        fatal_error = std::move(
            e.prefixed(fmt::format("{} setup failed", net::backend_name(setup_.backend))));
        return false;
    }
    loop_.set_direct(direct_);
    if (direct_) {
        if (Error e = net::register_socket_table(loop_.ring(), setup_.connections); !e.ok()) {
            fatal_error = Error(
                e.code(), fmt::format("io_uring socket table of {} slots failed: {} (a ring's "
                                      "table is capped at the open-files limit; more threads "
                                      "spread the connections over more rings)",
                                      setup_.connections, e.message()));
            return false;
        }
    }
    const unsigned count = std::clamp<unsigned>(std::bit_ceil(2 * setup_.connections), 64, 1024);
    if (Error e = loop_.init_buffers(kBufferGroup, count, 16384); !e.ok()) {
        fatal_error = std::move(e.prefixed("receive buffer setup failed"));
        return false;
    }
    return true;
}

void Worker::loop() noexcept {
    std::int64_t now = net::now_ns();
    update_stage(now);
    for (;;) {
        if (!started_ && now >= setup_.start_ns) begin_sending(now);
        if ((setup_.stop && setup_.stop->load(std::memory_order_relaxed)) ||
            setup_.abort->load(std::memory_order_relaxed) || now >= setup_.end_ns) {
            break;
        }
        if (quota_ != 0 && measured_sent_ >= quota_ && outstanding_ == 0) break;

        if (!connect_heap_.empty()) start_due_connects(now);
        if (open_loop_) issue_open_loop(now);
        if (now >= next_sweep_ns_) {
            sweep_timeouts(now);
            next_sweep_ns_ = now + sweep_interval_ns_;
        }
        flush();

        std::int64_t wake =
            std::min({setup_.end_ns, next_sweep_ns_, now + kMaxSleepNs, next_stage_update_ns_});
        if (!connect_heap_.empty()) {
            wake = std::min(wake, std::max(connect_heap_.front().first, next_connect_allowed_ns_));
        }
        if (open_loop_ && pacer_started_ && ready_size_ > 0 && may_send()) {
            wake = std::min(wake, pacer_.next_intended_ns());
        }
        if (now < setup_.measure_start_ns) wake = std::min(wake, setup_.measure_start_ns);
        if (!started_) wake = std::min(wake, setup_.start_ns);
        // A 1 us floor keeps the wait from becoming a pure poll; ready CQEs return at once.
        const std::int64_t wait = std::max<std::int64_t>(wake - now, 1000);
        const int rc = loop_.submit_and_wait(1, wait);
        if (net::wait_failed(rc)) {
            fatal_error = Error(ErrorCode::Io,
                                fmt::format("{} wait failed: {}", net::backend_name(setup_.backend),
                                            std::system_category().message(-rc)));
            setup_.abort->store(true);
            break;
        }
        now = net::now_ns();
        // Before any completion is handled, so no send at or past a boundary uses old targets.
        update_stage(now);
        if (now >= setup_.measure_start_ns) {
            interval_.tick(static_cast<std::uint64_t>(now - setup_.measure_start_ns),
                           *setup_.timeline, setup_.index);
        }
        loop_.drain([&](const net::Completion& cqe) { handle(cqe, now); });
        if (setup_.live != nullptr) {
            setup_.live->open_connections.set(open_connections.load(std::memory_order_relaxed));
            setup_.live->in_flight.set(outstanding_);
        }
    }
    finished_ns = now;
}

void Worker::teardown() noexcept {
    stopping_ = true;
    for (Connection& c : connections_) {
        c.table.abort_all([&](const Transaction& t) {
            if (t.sent_ns >= setup_.measure_start_ns) ++pending_at_end;
        });
        // A new generation makes every later completion stale: they only release resources.
        c.generation = net::next_generation(c.generation);
        c.recv_armed = false;
        if (c.fd >= 0) {
            if (direct_) {
                close_socket(c);
            } else if (loop_.uses_io_uring()) {
                ::shutdown(c.fd, SHUT_RDWR);
            } else {
                loop_.close(c.fd);  // its pending operations end now, -ECANCELED
                c.fd = -1;
            }
        }
        if (c.state == Connection::State::Open) open_connections.fetch_sub(1);
        c.state = Connection::State::Waiting;
    }
    outstanding_ = 0;
    if (finished_ns >= setup_.measure_start_ns) interval_.flush(*setup_.timeline, setup_.index);
    // Let the shut-down sockets' pending operations complete before closing and unmapping.
    const std::int64_t deadline = net::now_ns() + 200 * net::kNsPerMs;
    while (inflight_ops_ > 0) {
        const std::int64_t now = net::now_ns();
        if (now >= deadline) break;
        loop_.submit_and_wait(1, std::min<std::int64_t>(deadline - now, 10 * net::kNsPerMs));
        loop_.drain([&](const net::Completion& cqe) { handle(cqe, now); });
    }
    for (Connection& c : connections_) {
        if (c.fd >= 0 && !direct_) loop_.close(c.fd);  // direct: the ring's exit closes the table
        c.fd = -1;
    }
}

void Worker::begin_sending(std::int64_t now) noexcept {
    started_ = true;
    bool any_open = false;
    for (std::uint32_t i = 0; i < active_; ++i)
        any_open = any_open || connections_[i].state == Connection::State::Open;
    // Connected while waiting for the start: the schedule begins at the start itself, the
    // same instant on every machine of a sharded test.
    if (open_loop_ && !pacer_started_ && any_open) {
        pacer_ = Pacer(rate_, plan_.arrival, derive_seed(plan_.seed, 1000 + setup_.index),
                       setup_.start_ns);
        pacer_started_ = true;
    }
    for (std::uint32_t i = 0; i < active_; ++i) {
        if (connections_[i].state == Connection::State::Open) refill(i, now);
    }
}

void Worker::start_due_connects(std::int64_t now) noexcept {
    // Never bank more than a few ms of unused connect budget: no reconnect storms later.
    next_connect_allowed_ns_ = std::max(next_connect_allowed_ns_, now - 5 * net::kNsPerMs);
    while (!connect_heap_.empty() && connect_heap_.front().first <= now &&
           next_connect_allowed_ns_ <= now && !stopping_) {
        std::pop_heap(connect_heap_.begin(), connect_heap_.end(), kHeapOrder);
        const std::uint32_t index = connect_heap_.back().second;
        connect_heap_.pop_back();
        Connection& c = connections_[index];
        c.connect_queued = false;
        // A ramp down may have made it unwanted meanwhile; a ramp up re-queues it.
        if (index >= active_ || c.state != Connection::State::Waiting) continue;
        if (c.slot_closing) {  // its slot is still being emptied: a moment later
            queue_connect(index, now + net::kNsPerMs);
            continue;
        }
        next_connect_allowed_ns_ += connect_interval_ns_;
        start_connect(index, now);
        if (setup_.abort->load(std::memory_order_relaxed)) return;
    }
}

void Worker::queue_connect(std::uint32_t index, std::int64_t due) noexcept {
    Connection& c = connections_[index];
    if (c.connect_queued) return;
    c.connect_queued = true;
    connect_heap_.emplace_back(due, index);
    std::push_heap(connect_heap_.begin(), connect_heap_.end(), kHeapOrder);
}

std::uint32_t Worker::share_of(std::uint32_t total) const noexcept {
    const auto share =
        static_cast<std::uint32_t>(thread_share(total, setup_.threads, setup_.index));
    return std::min(share, setup_.connections);
}

void Worker::update_stage(std::int64_t now) noexcept {
    if (now < next_stage_update_ns_) return;
    apply_stage_targets(now);
    const std::int64_t offset = now - setup_.measure_start_ns;
    const std::int64_t boundary = setup_.schedule->next_boundary_ns(offset);
    next_stage_update_ns_ =
        std::min(now + kStageUpdateNs,
                 boundary == INT64_MAX ? INT64_MAX : setup_.measure_start_ns + boundary);
}

void Worker::apply_stage_targets(std::int64_t now) noexcept {
    const StageTargets t = setup_.schedule->at(now - setup_.measure_start_ns);
    set_active_connections(share_of(t.connections), now);
    if (!open_loop_) return;
    // Each thread paces its share of the rate over the connections it holds.
    rate_ = t.connections == 0 ? 0 : t.rate * active_ / t.connections;
    if (pacer_started_) pacer_.set_rate(rate_, now);
}

void Worker::set_active_connections(std::uint32_t count, std::int64_t now) noexcept {
    if (count == active_) return;
    const std::uint32_t before = active_;
    active_ = count;
    if (count > before) {
        for (std::uint32_t i = before; i < count; ++i) {
            Connection& c = connections_[i];
            if (c.state == Connection::State::Waiting) {
                queue_connect(i, now);
            } else if (c.state == Connection::State::Open) {
                refill(i, now);  // was draining: wanted again
            }
        }
    } else {
        // Surplus connections stop sending and close once their answers are in.
        for (std::uint32_t i = count; i < before; ++i) retire_if_idle(i);
    }
}

void Worker::retire_if_idle(std::uint32_t index) noexcept {
    Connection& c = connections_[index];
    if (index < active_ || c.state != Connection::State::Open || c.table.outstanding() != 0) return;
    drop_socket(c);
    c.ever_opened = false;  // opening it again later is not a reconnect after a failure
    c.backoff_ns = plan_.reconnect_backoff_min.count();
}

void Worker::refill(std::uint32_t index, std::int64_t now) noexcept {
    if (index >= active_) {
        retire_if_idle(index);
    } else if (open_loop_) {
        push_ready(index);
    } else {
        fill_closed_loop(index, now);
    }
}

void Worker::start_connect(std::uint32_t index, std::int64_t now) noexcept {
    Connection& c = connections_[index];
    const int fd = ::socket(setup_.endpoint.family(), SOCK_STREAM | SOCK_CLOEXEC, IPPROTO_TCP);
    if (fd < 0) {
        on_connect(index, -errno, now);
        return;
    }
    net::set_nodelay(fd);
    if (const int rc = bind_source(fd, index); rc < 0) {
        ::close(fd);
        on_connect(index, rc, now);
        return;
    }
    if (direct_) {
        if (const int rc = net::install_in_slot(loop_.ring(), index, fd); rc < 0) {
            on_connect(index, rc, now);
            return;
        }
        c.fd = static_cast<int>(index);
    } else {
        c.fd = fd;
    }
    c.state = Connection::State::Connecting;
    c.generation = net::next_generation(c.generation);
    c.connect_started_ns = now;
    loop_.connect(c.fd, setup_.endpoint.sa(), setup_.endpoint.len,
                  net::encode_user_data(Op::Connect, index, c.generation), &connect_timeout_ts_,
                  net::encode_user_data(Op::ConnectTimeout, index, c.generation));
    inflight_ops_ += 2;
}

int Worker::bind_source(int fd, std::uint32_t index) noexcept {
    if (setup_.sources == nullptr || setup_.sources->empty()) return 0;
    const std::vector<net::Endpoint>& sources = *setup_.sources;
    const std::uint32_t number = setup_.first_connection + index;
    net::Endpoint source = sources[number % sources.size()];
    // Each connection gets its own port of the ephemeral range on its address: the kernel's
    // own search for a free port walks the range, checking each port, on every connect, which
    // costs seconds per thousand connections once tens of thousands are open.
    const int one = 1;
    if (setup_.ports.size() > 0) {
        // A slot reconnecting finds its port's previous connection in TIME_WAIT.
        ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
        if (bind_own_or_spare_port(fd, source, number, connections_[index].port_shift)) return 0;
        source.set_port(0);  // none free: let the kernel pick at connect time
    }
    // Port 0: chosen at connect time, per destination (bind would take one for good).
    ::setsockopt(fd, SOL_IP, IP_BIND_ADDRESS_NO_PORT, &one, sizeof one);
    return ::bind(fd, source.sa(), source.len) == 0 ? 0 : -errno;
}

bool Worker::bind_own_or_spare_port(int fd, net::Endpoint& source, std::uint32_t number,
                                    std::uint32_t shift) noexcept {
    const std::uint32_t range = setup_.ports.size();
    const std::uint32_t own = number / static_cast<std::uint32_t>(setup_.sources->size());
    if (shift == 0 && own < range) {
        source.set_port(static_cast<std::uint16_t>(setup_.ports.low + own));
        if (::bind(fd, source.sa(), source.len) == 0) return true;
    }
    // Its own port is held by another socket (the target's listener, when the target is on
    // this machine and the kernel gave it a port of the range), or a connect from it failed:
    // the ports no connection owns, from the top of the range. Not another connection's port:
    // with SO_REUSEADDR the bind would share it and the connect then fail (EADDRNOTAVAIL).
    const std::uint32_t spare = range > setup_.ports_in_use ? range - setup_.ports_in_use : 0;
    for (std::uint32_t k = 0; k < std::min(kPortProbes, spare); ++k) {
        const std::uint32_t at = setup_.ports_in_use + (number + shift + k) % spare;
        source.set_port(static_cast<std::uint16_t>(setup_.ports.low + at));
        if (::bind(fd, source.sa(), source.len) == 0) return true;
    }
    return false;
}

void Worker::on_connect(std::uint32_t index, int result, std::int64_t now) noexcept {
    Connection& c = connections_[index];
    if (result == 0 && c.state == Connection::State::Connecting) {
        switch (c.link.connected(now, ktls_)) {
            case LinkStart::Open:
                break;
            case LinkStart::SettingUp:  // back here once the link is set up
                c.state = Connection::State::Handshaking;
                arm_recv(index);
                send_link_output(index);
                return;
            case LinkStart::SetUpFailed:
                link_error_ = c.link.error();
                result = kLinkSetUpFailed;
                break;
        }
    }
    if (result == 0) {
        c.state = Connection::State::Open;
        c.backoff_ns = plan_.reconnect_backoff_min.count();
        ++connection_stats.opened;
        if (setup_.live != nullptr) setup_.live->connections_opened.add();
        if (c.ever_opened) ++connection_stats.reconnects;
        c.ever_opened = true;
        setup_.any_connected->store(true, std::memory_order_relaxed);
        const std::uint32_t open = open_connections.fetch_add(1, std::memory_order_relaxed) + 1;
        connection_stats.peak_open = std::max<std::uint64_t>(connection_stats.peak_open, open);
        if (!c.recv_armed) arm_recv(index);
        if (open_loop_ && !pacer_started_ && started_) {
            pacer_ = Pacer(rate_, plan_.arrival, derive_seed(plan_.seed, 1000 + setup_.index), now);
            pacer_started_ = true;
        }
        refill(index, now);
        return;
    }
    ++connection_stats.failed;
    // A connect past its timeout ends -ECANCELED (its linked timeout fired): counted as such.
    const int cause = result == -ECANCELED ? ETIMEDOUT : -result;
    if (cause == EADDRNOTAVAIL) c.port_shift += kPortProbes;
    ++connect_failures_by_errno[static_cast<std::size_t>(cause) < connect_failures_by_errno.size()
                                    ? static_cast<std::size_t>(cause)
                                    : 0];
    // A link's set-up (a TLS handshake) that failed: refused, malformed or too slow.
    const bool handshake_failed = result == kLinkSetUpFailed;
    if (handshake_failed) ++connection_stats.tls_handshake_failures;
    if (setup_.live != nullptr) {
        setup_.live->connections_failed.add();
        if (handshake_failed) setup_.live->tls_handshake_failures.add();
    }
    close_socket(c);
    c.state = Connection::State::Waiting;
    c.generation = net::next_generation(c.generation);
    if (!setup_.any_connected->load(std::memory_order_relaxed)) {
        // Nothing ever connected: the target is wrong or down. Say so now, not after retries.
        const std::string reason =
            handshake_failed && !link_error_.empty() ? "TLS handshake failed: " + link_error_
            : result == -ECANCELED
                ? fmt::format("no answer within the connect timeout ({}s)",
                              std::chrono::duration<double>(plan_.connect_timeout).count())
                : std::system_category().message(-result);
        fatal_error = Error(ErrorCode::Network,
                            fmt::format("cannot connect to {}: {}", setup_.target, reason));
        setup_.abort->store(true);
        return;
    }
    schedule_reconnect(index, now);
}

void Worker::schedule_reconnect(std::uint32_t index, std::int64_t now) noexcept {
    if (stopping_) return;
    Connection& c = connections_[index];
    queue_connect(index, now + c.backoff_ns);
    const std::int64_t doubled = std::max<std::int64_t>(c.backoff_ns * 2, net::kNsPerMs);
    c.backoff_ns = std::min(doubled, plan_.reconnect_backoff_max.count());
}

void Worker::drop_socket(Connection& c) noexcept {
    if (c.state == Connection::State::Open)
        open_connections.fetch_sub(1, std::memory_order_relaxed);
    c.link.closed();
    close_socket(c);
    // A new generation makes the old socket's late completions stale.
    c.generation = net::next_generation(c.generation);
    c.state = Connection::State::Waiting;
    c.queued = 0;
    c.recv_armed = false;
}

void Worker::close_socket(Connection& c) noexcept {
    if (c.fd < 0) return;
    if (direct_) {
        // The shutdown ends the pending multishot recv.
        const auto index = static_cast<std::uint32_t>(c.fd);
        if (loop_.shutdown_and_close_slot(index,
                                          net::encode_user_data(Op::Shutdown, index, c.generation),
                                          net::encode_user_data(Op::Close, index, c.generation))) {
            inflight_ops_ += 2;
            c.slot_closing = true;
        }
    } else {
        loop_.shutdown_and_close(c.fd);
    }
    c.fd = -1;
}

void Worker::close_connection(std::uint32_t index, std::int64_t now, stats::Outcome why) noexcept {
    Connection& c = connections_[index];
    c.table.abort_all([&](const Transaction& t) {
        --outstanding_;
        record(t, why, 0, now);
    });
    drop_socket(c);
    schedule_reconnect(index, now);
}

void Worker::arm_recv(std::uint32_t index) noexcept {
    Connection& c = connections_[index];
    if (!loop_.recv(c.fd, net::encode_user_data(Op::Recv, index, c.generation), multishot_)) return;
    c.recv_armed = true;
    ++inflight_ops_;
}

void Worker::handle(const net::Completion& cqe, std::int64_t now) noexcept {
    const net::UserData ud = net::decode_user_data(cqe.user_data);
    if (ud.index >= connections_.size()) return;
    switch (static_cast<Op>(ud.op)) {
        case Op::ConnectTimeout:
            --inflight_ops_;
            return;
        case Op::Connect:
            --inflight_ops_;
            if (ud.generation == connections_[ud.index].generation && !stopping_) {
                on_connect(ud.index, cqe.res, now);
            }
            return;
        case Op::Recv:
            on_recv(ud.index, cqe, now);
            return;
        case Op::Send:
            on_send(ud.index, cqe, now);
            return;
        case Op::Shutdown:
            --inflight_ops_;
            return;
        case Op::Close:
            --inflight_ops_;
            connections_[ud.index].slot_closing = false;
            return;
    }
}

void Worker::note_unframed(codec::Bytes input) noexcept {
    unframed_bytes += input.size();
    if (unframed_sample_size != 0) return;
    unframed_sample_size =
        static_cast<std::uint8_t>(std::min(input.size(), unframed_sample.size()));
    std::copy_n(input.begin(), unframed_sample_size, unframed_sample.begin());
}

void Worker::on_recv(std::uint32_t index, const net::Completion& cqe, std::int64_t now) noexcept {
    Connection& c = connections_[index];
    const net::UserData ud = net::decode_user_data(cqe.user_data);
    const bool more = (cqe.flags & IORING_CQE_F_MORE) != 0;
    const bool has_buffer = net::BufRing::has_buffer(cqe.flags);
    const std::uint16_t buffer_id = net::BufRing::buffer_id(cqe.flags);
    if (!more) --inflight_ops_;
    if (ud.generation != c.generation || stopping_) {
        if (has_buffer) loop_.recycle(buffer_id);
        return;
    }
    if (!more) c.recv_armed = false;
    if (cqe.res <= 0 || !has_buffer) {
        if (has_buffer) loop_.recycle(buffer_id);
        on_recv_ended(index, cqe.res, now);
        return;
    }
    const codec::Bytes input(loop_.buffer(buffer_id), static_cast<std::size_t>(cqe.res));
    codec::Bytes plain;
    LinkInput got = c.link.take(input, now, link_scratch_, plain);
    if (got == LinkInput::Answers || got == LinkInput::SetUp) {
        codec::TcpFrame frame;
        LinkInput end = LinkInput::Answers;
        while (c.link.next_answer(frame, bad_protocol_frames, end)) on_answer(c, frame, now);
        if (end != LinkInput::Answers) got = end;
        if (got == LinkInput::FramingLost) note_unframed(plain);  // it may be the buffer's
    }
    loop_.recycle(buffer_id);
    if (got != LinkInput::Answers && !on_link_event(index, got, now)) return;
    send_link_output(index);  // tickets, key updates
    if (!try_hand_off(index, now)) return;
    if (!c.recv_armed) arm_recv(index);
    refill(index, now);
}

void Worker::on_recv_ended(std::uint32_t index, int result, std::int64_t now) noexcept {
    Connection& c = connections_[index];
    if (result == -ENOBUFS) {  // the buffer ring ran dry for a moment: listen again
        arm_recv(index);
        return;
    }
    if (result > 0) return;  // cannot happen with buffer select; nothing to read
    if (c.link.is_record_layer_error(result)) {
        ++connection_stats.tls_offload_errors;
        if (setup_.live != nullptr) setup_.live->tls_offload_errors.add();
    }
    ++connection_stats.closed_by_peer;
    if (setup_.live != nullptr) setup_.live->connections_closed_by_peer.add();
    close_connection(index, now, stats::Outcome::ConnectionClosed);
}

bool Worker::on_answer(Connection& c, const codec::TcpFrame& frame, std::int64_t now) noexcept {
    Transaction* t = nullptr;
    switch (c.table.complete(frame.header.transaction_id, t)) {
        case MatchResult::Matched:
            break;
        case MatchResult::Unknown:
            if (now >= setup_.measure_start_ns) {
                stray.record(stats::Outcome::UnknownId);
                stray.bytes_received += frame.adu.size();
                if (setup_.live != nullptr) {
                    setup_.live->stray[static_cast<std::size_t>(stats::Outcome::UnknownId)].add();
                    setup_.live->stray_bytes.add(frame.adu.size());
                }
            }
            return false;
        case MatchResult::Duplicate:
            if (now >= setup_.measure_start_ns) {
                stray.record(stats::Outcome::DuplicateId);
                stray.bytes_received += frame.adu.size();
                if (setup_.live != nullptr) {
                    setup_.live->stray[static_cast<std::size_t>(stats::Outcome::DuplicateId)].add();
                    setup_.live->stray_bytes.add(frame.adu.size());
                }
            }
            return false;
        case MatchResult::Late:
            ++late_responses;
            return false;
    }
    --outstanding_;
    c.answered_up_to = std::max(c.answered_up_to, t->sequence + 1);
    if (t->sent_ns >= setup_.measure_start_ns) {
        operations[t->request.op_index].counters.bytes_received += frame.adu.size();
        if (setup_.live != nullptr)
            setup_.live->operations[t->request.op_index].bytes_received.add(frame.adu.size());
        if (setup_.schedule != nullptr) {
            stats::StageResult& stage = stages[setup_.schedule->stage_at(
                (open_loop_ ? t->intended_ns : t->sent_ns) - setup_.measure_start_ns)];
            stage.counters.bytes_received += frame.adu.size();
            if (!stage.operations.empty())
                stage.operations[t->request.op_index].counters.bytes_received += frame.adu.size();
        }
    }
    stats::Outcome outcome = stats::Outcome::Ok;
    std::uint8_t exception_code = 0;
    if (is_expected_read_answer(t->request, frame)) {
        if (setup_.verifier.check == nullptr) {
            record(*t, stats::Outcome::Ok, 0, now);  // a constant outcome: its checks fold away
            return true;
        }
        // The decoded response is built only for a value verifier.
        response_scratch_ = codec::Response{};
        response_scratch_.function = t->request.function;
        response_scratch_.payload = frame.pdu.subspan(2);
    } else {
        outcome = check_response(t->request, frame, response_scratch_);
        exception_code = static_cast<std::uint8_t>(response_scratch_.exception);
    }
    if (outcome == stats::Outcome::Ok && setup_.verifier.check != nullptr &&
        !setup_.verifier.check(setup_.verifier.context, t->request, response_scratch_)) {
        outcome = stats::Outcome::ValueMismatch;
    }
    record(*t, outcome, exception_code, now);
    return true;
}

void Worker::on_send(std::uint32_t index, const net::Completion& cqe, std::int64_t now) noexcept {
    Connection& c = connections_[index];
    --inflight_ops_;
    const net::UserData ud = net::decode_user_data(cqe.user_data);
    if (ud.generation != c.generation || stopping_) {
        // The socket it went to is gone; its buffer half is free again.
        c.send_in_flight = false;
        if (!stopping_) send_link_output(index);  // a new connection's set-up waited
        if (c.state == Connection::State::Open && c.queued > 0) dirty_.mark(c.dirty, index);
        return;
    }
    if (cqe.res < 0) {
        c.send_in_flight = false;
        close_connection(index, now, stats::Outcome::ConnectionClosed);
        return;
    }
    c.inflight_done += static_cast<std::uint32_t>(cqe.res);
    if (c.inflight_done < c.inflight_len) {  // short send: the rest goes next
        loop_.send(c.fd, c.inflight_base + c.inflight_done, c.inflight_len - c.inflight_done,
                   net::encode_user_data(Op::Send, index, c.generation));
        ++inflight_ops_;
        return;
    }
    c.send_in_flight = false;
    send_link_output(index);
    if (c.queued > 0) dirty_.mark(c.dirty, index);
}

Transaction* Worker::enqueue(std::uint32_t index, std::int64_t now, std::int64_t intended,
                             std::uint32_t& size) noexcept {
    Connection& c = connections_[index];
    const std::uint32_t room = c.send_half - c.queued;
    Transaction* t = c.table.begin(now, intended);
    if (t == nullptr) return nullptr;
    std::size_t written = generator_.next(
        t->transaction_id(), codec::MutableBytes(c.queue_data() + c.queued, room), t->request);
    if (written == 0) {
        c.table.cancel(t);
        return nullptr;
    }
    written = c.link.frame_request(c.queue_data() + c.queued, written, t->transaction_id());
    size = static_cast<std::uint32_t>(written);
    c.queued += size;
    ++outstanding_;
    if (now >= setup_.measure_start_ns) ++measured_sent_;
    dirty_.mark(c.dirty, index);
    return t;
}

void Worker::count_sent(std::uint16_t op_index, std::uint64_t count, std::uint64_t bytes,
                        std::int64_t intended) noexcept {
    stats::OutcomeCounters& op = operations[op_index].counters;
    op.transactions_sent += count;
    op.bytes_sent += bytes;
    if (setup_.live != nullptr) {
        setup_.live->operations[op_index].sent.add(count);
        setup_.live->operations[op_index].bytes_sent.add(bytes);
    }
    if (setup_.schedule != nullptr) {
        stats::StageResult& stage =
            stages[setup_.schedule->stage_at(intended - setup_.measure_start_ns)];
        stage.counters.transactions_sent += count;
        stage.counters.bytes_sent += bytes;
        if (!stage.operations.empty()) {
            stage.operations[op_index].counters.transactions_sent += count;
            stage.operations[op_index].counters.bytes_sent += bytes;
        }
    }
}

void Worker::fill_closed_loop(std::uint32_t index, std::int64_t now) noexcept {
    Connection& c = connections_[index];
    if (c.state != Connection::State::Open || index >= active_ || !may_send()) return;
    // Nothing in a fill changes the connection's state, whether it is wanted or whether the run
    // stops, so how many requests it may queue is known before the first: the free depth, and
    // what is left of a quota (which counts measured sends only).
    const bool measured = now >= setup_.measure_start_ns;
    const std::uint32_t outstanding = c.table.outstanding();
    std::uint64_t budget = outstanding < plan_.depth ? plan_.depth - outstanding : 0;
    if (quota_ != 0 && measured) budget = std::min(budget, quota_ - measured_sent_);
    // Every request of this fill is sent (and meant to be sent) now, so they share a stage and
    // whether they are measured; with one operation they are counted once, together.
    const bool together = operations.size() == 1;
    std::uint64_t sent = 0, bytes = 0;
    for (; budget > 0; --budget) {
        std::uint32_t size = 0;
        const Transaction* t = enqueue(index, now, now, size);
        if (t == nullptr) break;
        if (together) {
            ++sent;
            bytes += size;
        } else if (measured) {
            count_sent(t->request.op_index, 1, size, now);
        }
    }
    if (measured && sent != 0) count_sent(0, sent, bytes, now);
}

void Worker::push_ready(std::uint32_t index) noexcept {
    Connection& c = connections_[index];
    if (c.in_ready || c.state != Connection::State::Open || index >= active_ ||
        c.table.outstanding() >= plan_.depth) {
        return;
    }
    ready_[(ready_head_ + ready_size_) % ready_.size()] = index;
    ++ready_size_;
    c.in_ready = true;
}

void Worker::issue_open_loop(std::int64_t now) noexcept {
    if (!pacer_started_) return;
    while (pacer_.due(now) && may_send() && ready_size_ > 0) {
        const std::uint32_t index = ready_[ready_head_];
        ready_head_ = (ready_head_ + 1) % ready_.size();
        --ready_size_;
        Connection& c = connections_[index];
        c.in_ready = false;
        if (c.state != Connection::State::Open || index >= active_ ||
            c.table.outstanding() >= plan_.depth)
            continue;
        const std::int64_t intended = pacer_.next_intended_ns();
        std::uint32_t size = 0;
        const Transaction* t = enqueue(index, now, intended, size);
        if (t == nullptr) continue;
        if (now >= setup_.measure_start_ns) count_sent(t->request.op_index, 1, size, intended);
        lag_.record(intended, now, now >= setup_.measure_start_ns);
        pacer_.advance();
        push_ready(index);
    }
    // Due, allowed, and no connection can take it: the send waits for the target.
    if (ready_size_ == 0 && pacer_.due(now) && may_send() && !pacer_.paused()) {
        lag_.note_window_full();
    }
}

void Worker::flush() noexcept {
    dirty_.drain([this](std::uint32_t index) {
        Connection& c = connections_[index];
        c.dirty = false;
        if (c.state != Connection::State::Open || c.send_in_flight || c.queued == 0) return;
        codec::Bytes wire;
        if (!c.link.seal(c.queue_data(), c.queued, wire)) {
            close_connection(index, net::now_ns(), stats::Outcome::ConnectionClosed);
            return;
        }
        // The queue half itself goes, or the link took its bytes into its own (ciphertext).
        const bool own_half = wire.data() == c.queue_data();
        if (!own_half) c.queued = 0;
        if (wire.empty() || !start_send(index, wire) || !own_half) return;
        c.queue_half ^= 1u;
        c.queued = 0;
    });
}

void Worker::sweep_timeouts(std::int64_t now) noexcept {
    const std::int64_t deadline = now - plan_.transaction_timeout.count();
    for (std::uint32_t index = 0; index < connections_.size(); ++index) {
        Connection& c = connections_[index];
        if (c.state == Connection::State::Handshaking) check_set_up_time(index, now);
        if (c.state != Connection::State::Open || c.table.outstanding() == 0) continue;
        const std::uint32_t expired = c.table.expire(deadline, [&](const Transaction& t) {
            --outstanding_;
            if (t.sequence + 1 < c.answered_up_to && t.sent_ns >= setup_.measure_start_ns)
                ++skipped_requests;
            record(t, stats::Outcome::Timeout, 0, now);
        });
        if (expired == 0) continue;
        if (!c.link.matches_answers_by_id()) {
            // No transaction ids: on this connection the late answer would pass for the next
            // request's. A fresh connection leaves it nowhere to land.
            drop_socket(c);
            schedule_reconnect(index, now);
            continue;
        }
        refill(index, now);
    }
}

void Worker::record(const Transaction& t, stats::Outcome outcome, std::uint8_t exception_code,
                    std::int64_t now) noexcept {
    if (t.sent_ns < setup_.measure_start_ns) return;  // warm-up
    // Open loop: from the intended send time, so queueing delay is never hidden.
    const std::int64_t from = open_loop_ ? t.intended_ns : t.sent_ns;
    const auto latency = static_cast<std::uint64_t>(std::max<std::int64_t>(now - from, 0));
    const bool answered = has_response(outcome);
    if (answered && open_loop_)
        service_time.record(static_cast<std::uint64_t>(std::max<std::int64_t>(now - t.sent_ns, 0)));
    auto count = [&](stats::OperationResult& into, bool with_latency) {
        if (outcome == stats::Outcome::Exception) {
            into.counters.record_exception(exception_code);
        } else {
            into.counters.record(outcome);
        }
        if (answered && with_latency) into.latency.record(latency);
    };
    // Up to kMaxOperationsRecordedOnce operations, latencies reach the operation's histogram
    // through the interval recorder.
    count(operations[t.request.op_index], operations.size() != 1 && !latency_by_operation_);
    if (setup_.live != nullptr)
        setup_.live->record(t.request.op_index, outcome, exception_code, answered, latency);
    if (setup_.schedule != nullptr) {
        // A transaction belongs to the stage it was (meant to be) sent in.
        stats::StageResult& stage =
            stages[setup_.schedule->stage_at(from - setup_.measure_start_ns)];
        if (outcome == stats::Outcome::Exception) {
            stage.counters.record_exception(exception_code);
        } else {
            stage.counters.record(outcome);
        }
        if (answered) stage.latency.record(latency);
        if (!stage.operations.empty()) count(stage.operations[t.request.op_index], true);
    }
    if (answered) {
        if (latency_by_operation_) {
            interval_.record_tagged(latency, t.request.op_index);
        } else {
            interval_.record_latency(latency, t.request.op_index);
        }
    }
    interval_.record_transaction(outcome != stats::Outcome::Ok);
}

}  // namespace mbstorm::load
