// One engine thread: its ring, buffer ring, connections, generator, pacer and results.
#pragma once

#include <array>
#include <atomic>
#include <cerrno>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "codec/pdu.hpp"
#include "load/connection.hpp"
#include "load/engine.hpp"
#include "load/live_metrics.hpp"
#include "load/operation_generator.hpp"
#include "load/pacer.hpp"
#include "load/plan.hpp"
#include "load/preflight.hpp"
#include "load/stage_schedule.hpp"
#include "net/completion_loop.hpp"
#include "net/event_loop.hpp"
#include "net/socket.hpp"
#include "net/user_data.hpp"
#include "stats/interval_recorder.hpp"
#include "stats/run_result.hpp"
#include "util/error.hpp"

namespace mbstorm::load {

struct WorkerSetup {
    const Plan* plan = nullptr;
    net::Endpoint endpoint;
    // Local addresses to bind to, round-robin by connection number (empty: the kernel picks).
    const std::vector<net::Endpoint>* sources = nullptr;
    std::uint32_t first_connection = 0;  // number of this thread's first connection in the run
    PortRange ports{1, 0};               // ephemeral ports given out with `sources` (size 0: none)
    std::uint32_t ports_in_use = 0;      // of them, owned by a connection number (per address)
    std::string target;                  // for messages
    std::uint32_t index = 0;
    std::uint32_t threads = 1;
    std::uint32_t connections = 1;      // this thread's share of the peak connection count
    std::uint64_t quota = 0;            // measured transactions this thread sends; 0: unlimited
    double rate = 0;                    // open loop: this thread's share
    double connect_rate = 1;            // this thread's share
    std::int64_t connect_start_ns = 0;  // connections open from here
    std::int64_t start_ns = 0;          // requests from here (run --start-at: later)
    std::int64_t measure_start_ns = 0;  // end of warm-up
    std::int64_t end_ns = INT64_MAX;
    const std::atomic<bool>* stop = nullptr;
    std::atomic<bool>* abort = nullptr;  // set by any worker on a fatal error
    std::atomic<bool>* any_connected = nullptr;
    ResponseVerifier verifier;
    stats::IntervalTimeline* timeline = nullptr;
    const StageSchedule* schedule = nullptr;  // staged runs only
    // Hold sockets as io_uring direct descriptors (the engine checked the kernel has them and
    // that `connections` fits a ring's table).
    bool direct_descriptors = false;
    net::Backend backend = net::Backend::IoUring;
    LiveWorkerCells* live = nullptr;  // --metrics-listen only
};

class Worker {
  public:
    explicit Worker(WorkerSetup setup);
    void run() noexcept;

    // Results, valid after run() returned.
    std::vector<stats::OperationResult> operations;
    std::vector<stats::StageResult> stages;  // staged runs: by the stage a transaction was sent in
    stats::Histogram service_time;           // open loop: answers timed from their actual send
    stats::OutcomeCounters stray;            // UnknownId / DuplicateId and their bytes
    stats::ScheduleLag schedule_lag;
    stats::ConnectionStats connection_stats;
    // Failed connects by errno (connection_stats.failed by cause; the engine names them).
    std::array<std::uint64_t, 160> connect_failures_by_errno{};
    std::uint64_t pending_at_end = 0;
    std::uint64_t late_responses = 0;
    std::uint64_t framing_errors = 0;
    // Bytes of the receives whose stream could not be framed (what `received` leaves out), and
    // the first such receive's first bytes: they say what the target speaks instead.
    std::uint64_t unframed_bytes = 0;
    std::array<std::uint8_t, 16> unframed_sample{};
    std::uint8_t unframed_sample_size = 0;
    std::uint64_t crc_errors = 0;  // RTU over TCP: answers with a bad CRC (connection reset)
    std::uint64_t bad_protocol_frames = 0;
    std::uint64_t skipped_requests = 0;  // see stats::PipeliningSigns
    std::int64_t finished_ns = 0;
    Error fatal_error;  // what ended the run early, if anything did
    std::atomic<std::uint32_t> open_connections{0};

  private:
    // What a completion is for (the op field of its user_data).
    enum class Op : std::uint8_t { Connect = 1, ConnectTimeout, Recv, Send, Shutdown, Close };
    // on_connect's result for a link whose set-up (a TLS handshake) failed or timed out.
    static constexpr int kLinkSetUpFailed = -EPROTO;

    bool setup_io() noexcept;
    void loop() noexcept;
    void teardown() noexcept;

    void start_due_connects(std::int64_t now) noexcept;
    void queue_connect(std::uint32_t index, std::int64_t due) noexcept;
    void update_stage(std::int64_t now) noexcept;  // staged runs: at most every 10 ms
    void apply_stage_targets(std::int64_t now) noexcept;
    void set_active_connections(std::uint32_t count, std::int64_t now) noexcept;
    void retire_if_idle(std::uint32_t index) noexcept;
    std::uint32_t share_of(std::uint32_t total) const noexcept;
    void start_connect(std::uint32_t index, std::int64_t now) noexcept;
    // Binds a connection's socket to its source address, if the run has any: 0 or -errno.
    int bind_source(int fd, std::uint32_t index) noexcept;
    // Binds connection `number`'s own port of the range, else a spare one: false when none.
    bool bind_own_or_spare_port(int fd, net::Endpoint& source, std::uint32_t number,
                                std::uint32_t shift) noexcept;
    void on_connect(std::uint32_t index, int result, std::int64_t now) noexcept;
    void close_connection(std::uint32_t index, std::int64_t now, stats::Outcome why) noexcept;
    void drop_socket(Connection& c) noexcept;   // closes it; the connection waits to reopen
    void close_socket(Connection& c) noexcept;  // direct: until its close completes, no reopen
    void schedule_reconnect(std::uint32_t index, std::int64_t now) noexcept;
    void arm_recv(std::uint32_t index) noexcept;
    // Errors first: a receive that ended (the peer closed, a failed recv) or brought no
    // buffer; then the bytes go to the connection's link, which hands on the answers.
    void on_recv(std::uint32_t index, const net::Completion& cqe, std::int64_t now) noexcept;
    void on_recv_ended(std::uint32_t index, int result, std::int64_t now) noexcept;
    void note_unframed(codec::Bytes input) noexcept;
    // An answer's frame: matched to its transaction, checked and recorded (inlined into the
    // link's frame loop: as a call, its prologue and epilogue were about 18 instructions per
    // answer).
    [[gnu::always_inline]] inline bool on_answer(Connection& c, const codec::TcpFrame& frame,
                                                 std::int64_t now) noexcept;
    void on_send(std::uint32_t index, const net::Completion& cqe, std::int64_t now) noexcept;
    void handle(const net::Completion& cqe, std::int64_t now) noexcept;
    // Sends `wire` on the connection (no send of it in flight): false when it could not go.
    // Inline: once per flush of every connection, where the call was a cost of its own.
    [[gnu::always_inline]] bool start_send(std::uint32_t index, codec::Bytes wire) noexcept {
        Connection& c = connections_[index];
        if (!loop_.send(c.fd, wire.data(), static_cast<unsigned>(wire.size()),
                        net::encode_user_data(Op::Send, index, c.generation)))
            return false;
        ++inflight_ops_;
        c.inflight_base = wire.data();
        c.inflight_len = static_cast<std::uint32_t>(wire.size());
        c.inflight_done = 0;
        c.send_in_flight = true;
        return true;
    }

    // What the links say (worker_link.cpp). on_link_event: anything but answers from a link's
    // input; true when the connection is open and goes on. send_link_output: bytes the link
    // itself has to send (a handshake's, tickets). try_hand_off: the kernel's TLS takes the
    // link's record layer when it can now; false when a half-done hand-off closed it.
    bool on_link_event(std::uint32_t index, LinkInput event, std::int64_t now) noexcept;
    // Inline for the plain links' sake: once per receive and per send, a call each was a cost.
    void send_link_output(std::uint32_t index) noexcept {
        if (connections_[index].link.may_have_output()) send_link_bytes(index);
    }
    void send_link_bytes(std::uint32_t index) noexcept;
    bool try_hand_off(std::uint32_t index, std::int64_t now) noexcept {
        return !ktls_ || hand_off_now(index, now);
    }
    bool hand_off_now(std::uint32_t index, std::int64_t now) noexcept;
    void count_set_up(const Link& link) noexcept;  // a handshake done: timed and counted
    // A session refused before any answer (a TLS alert after the handshake): stop the run.
    void link_refused(const std::string& why) noexcept;
    // A set-up gets the connect timeout too: a peer that accepts and never answers fails.
    void check_set_up_time(std::uint32_t index, std::int64_t now) noexcept;

    bool may_send() const noexcept {
        return started_ && !stopping_ && (quota_ == 0 || measured_sent_ < quota_);
    }
    // Queues one request; nullptr when none could be. Counts what the quota counts, not the
    // per-operation statistics: count_sent() adds those, per request or per fill. Inlined into
    // its two callers (worker.cpp): as a call its prologue was a tenth of its cost.
    [[gnu::always_inline]] inline Transaction* enqueue(std::uint32_t index, std::int64_t now,
                                                       std::int64_t intended,
                                                       std::uint32_t& size) noexcept;
    void count_sent(std::uint16_t op_index, std::uint64_t count, std::uint64_t bytes,
                    std::int64_t intended) noexcept;
    void fill_closed_loop(std::uint32_t index, std::int64_t now) noexcept;
    void refill(std::uint32_t index, std::int64_t now) noexcept;  // after answers or timeouts
    void issue_open_loop(std::int64_t now) noexcept;
    void push_ready(std::uint32_t index) noexcept;
    void flush() noexcept;
    void begin_sending(std::int64_t now) noexcept;  // at setup_.start_ns
    void sweep_timeouts(std::int64_t now) noexcept;
    // Inlined where it is called (all in worker.cpp): as a call, its saved registers and
    // arguments were 16-20 of the engine's ~540 instructions per transaction.
    [[gnu::always_inline]] inline void record(const Transaction& t, stats::Outcome outcome,
                                              std::uint8_t exception_code,
                                              std::int64_t now) noexcept;

    WorkerSetup setup_;
    const Plan& plan_;
    bool open_loop_;
    std::uint64_t quota_;
    std::uint64_t measured_sent_ = 0;  // sends after warm-up: what the quota counts
    std::uint64_t outstanding_ = 0;    // over all connections
    std::int64_t inflight_ops_ = 0;    // ring operations not yet completed (for teardown)
    bool stopping_ = false;
    bool started_ = false;  // past setup_.start_ns: requests may go out

    net::EventLoop loop_;
    bool multishot_ = true;
    bool direct_ = false;  // sockets are slots of the ring's file table (slot = connection index)
    bool ktls_ = false;    // TLS connections are handed to the kernel's TLS when they can be

    std::vector<Connection> connections_;
    OperationGenerator generator_;
    Pacer pacer_;
    bool pacer_started_ = false;
    double rate_ = 0;           // open loop: this thread's current rate
    std::uint32_t active_ = 0;  // connections [0, active_) are wanted open; the rest drain
    std::int64_t next_stage_update_ns_ = INT64_MAX;
    LagTracker lag_;
    stats::IntervalRecorder interval_;
    bool latency_by_operation_ = false;  // several operations, recorded once (see the ctor)

    net::DirtyList dirty_;              // connections with queued bytes
    std::vector<std::uint32_t> ready_;  // open loop: ring of connections with spare depth
    std::size_t ready_head_ = 0, ready_size_ = 0;
    std::vector<std::pair<std::int64_t, std::uint32_t>> connect_heap_;  // (due, index), min-heap
    std::int64_t next_connect_allowed_ns_ = 0;
    std::int64_t connect_interval_ns_ = 0;
    std::int64_t next_sweep_ns_ = 0;
    std::int64_t sweep_interval_ns_ = 0;
    __kernel_timespec connect_timeout_ts_{};
    codec::Response response_scratch_;
    std::vector<std::uint8_t> link_scratch_;  // decrypted input of one recv (TLS links')
    std::string link_error_;                  // why the last link set-up failed
    bool links_answered_ = false;             // a link here has carried an answer's bytes
};

}  // namespace mbstorm::load
