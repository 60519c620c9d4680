// One server thread: one io_uring, one listener (SO_REUSEPORT), its connections, its buffer
// ring and output pool. Everything here runs on the worker's own thread except
// request_stop() and counters().
#pragma once

#include <atomic>
#include <cstdint>
#include <vector>

#include "net/completion_loop.hpp"
#include "net/event_loop.hpp"
#include "server/config.hpp"
#include "server/connection.hpp"
#include "server/connection_table.hpp"
#include "server/stats.hpp"
#include "slave/faults.hpp"

namespace mbstorm::slave {
class DataModel;
}

namespace mbstorm::server {

class Worker {
  public:
    Worker(const ServerConfig& config, slave::DataModel& model, int listen_fd, unsigned index,
           std::atomic<std::uint32_t>& open_connections, std::uint64_t stall_origin_ns);
    ~Worker();
    Worker(const Worker&) = delete;
    Worker& operator=(const Worker&) = delete;

    // Thread body. Sets init_status() to 1 once serving or to -1 when setup failed, and then
    // setup_error() says why (read it after init_status() is -1).
    void run() noexcept;
    int init_status() const noexcept { return init_status_.load(std::memory_order_acquire); }
    const Error& setup_error() const noexcept { return setup_error_; }
    void request_stop() noexcept;  // any thread
    const ServerCounters& counters() const noexcept { return counters_; }
    unsigned index() const noexcept { return index_; }
    // Bytes of fixed per-connection state (for the memory report).
    static std::size_t connection_bytes() noexcept { return sizeof(Connection); }
    std::size_t buf_ring_bytes() const noexcept { return loop_.buffer_memory_bytes(); }

    // Max-connections with the evict-oldest-idle policy over several threads: each worker
    // publishes the last activity of its oldest idle connection, and the worker that accepts
    // at the limit asks the one holding the server-wide oldest to close it. Set before run().
    void set_peers(std::vector<Worker*> peers) { peers_ = std::move(peers); }
    void request_eviction() noexcept;  // any thread

    // Hold accepted sockets as io_uring direct descriptors in a table of `slots` (0: plain
    // descriptors). Set before run(); falls back to plain descriptors if the table cannot be
    // registered.
    void set_socket_table(unsigned slots) noexcept { table_slots_ = slots; }
    bool direct_descriptors() const noexcept { return direct_; }

  private:
    // What a completion is for (the op field of its user_data).
    enum class Op : std::uint8_t {
        Accept = 1,
        Recv,
        Send,
        Stop,
        Cancel,
        AcceptPause,
        Mail,
        SocketShutdown,
        SocketClose
    };

    Error setup() noexcept;
    void loop() noexcept;
    void shutdown_all() noexcept;
    void on_cqe(const net::Completion& cqe) noexcept;
    void on_accept(const net::Completion& cqe) noexcept;
    void on_recv(const net::Completion& cqe) noexcept;
    void on_send(const net::Completion& cqe) noexcept;

    void arm_accept() noexcept;
    // Out of file descriptors: re-arms the accept after a growing pause (an io_uring timeout,
    // so open connections are served meanwhile) instead of spinning on EMFILE.
    void pause_accept() noexcept;
    void arm_stop() noexcept;
    void arm_mail() noexcept;
    void serve_evictions() noexcept;  // eviction requests from other workers
    // The connection an eviction closes: the oldest still in its TLS handshake, else the
    // least recently active.
    std::uint32_t eviction_victim() const noexcept;
    // A TLS connection admitted over the limit has authenticated: the oldest idle one goes.
    void make_room_after_handshake(std::uint32_t index) noexcept;
    void publish_oldest_idle() noexcept;
    bool evict_server_wide_oldest() noexcept;  // false: nothing idle anywhere
    void arm_recv(std::uint32_t index) noexcept;
    void cancel_recv(std::uint32_t index) noexcept;
    void admit(int fd) noexcept;
    void close_connection(std::uint32_t index) noexcept;
    void close_socket(int fd) noexcept;  // a descriptor, or a slot with direct descriptors
    void maybe_release(std::uint32_t index) noexcept;

    void stash(std::uint32_t index, std::uint16_t bid, std::uint32_t size) noexcept;
    void drain_stash(std::uint32_t index) noexcept;
    void drop_stash(std::uint32_t index) noexcept;
    // Pauses reading when the output queue is over the cap. True when paused.
    bool check_backpressure(std::uint32_t index) noexcept;
    // Bytes from the socket go to the connection's link; the worker reads the requests from
    // it (on_frame for each), then does what the link said.
    void consume_input(std::uint32_t index, const std::uint8_t* data, std::size_t size) noexcept;
    // Frames a link dropped: MBAP frames with a wrong protocol id, RTU frames with a bad CRC.
    void count_dropped_frames(std::uint64_t discarded, std::uint64_t crc_skipped) noexcept {
        if (discarded != 0) counters_.add(ServerCounters::DiscardedFrames, discarded);
        if (crc_skipped != 0) counters_.add(ServerCounters::CrcErrors, crc_skipped);
    }
    // What the links say (worker_link.cpp). on_link_event: anything but "drained" from a
    // link's input; true when the connection goes on to after_link_input (frame clock for a
    // partial TLS record, the link's own output, the kernel hand-off).
    bool on_link_event(std::uint32_t index, LinkInput event) noexcept;
    void on_link_set_up(std::uint32_t index) noexcept;  // a TLS handshake done
    void after_link_input(std::uint32_t index) noexcept;
    // The set-up failed: the alert goes out, then the connection closes.
    void link_refused(std::uint32_t index) noexcept;
    // Hands the link's record layer to the kernel's TLS when it can take it now.
    void try_hand_off(std::uint32_t index) noexcept;
    // Tracks when the partial frame the splitter holds began (frame timeout).
    void note_partial_frame(Connection& c, std::uint32_t index, bool frame_completed) noexcept;
    // Times what arrived so far against --frame-timeout (a frame, or a TLS handshake).
    void start_frame_clock(Connection& c, std::uint32_t index) noexcept;
    // Framing was lost: answer what came before, read no more, close once answered.
    // `crc`: an RTU frame's CRC failed (counted as such, not as a bad length).
    void lose_framing(std::uint32_t index, bool crc = false) noexcept;
    // Closes a connection whose input is over once every answer has gone out.
    void close_if_answered(std::uint32_t index) noexcept;
    // False when the connection was closed (fault drop).
    // `c` is conns_[index], passed along so the hot path indexes the table once per frame.
    // Marks nothing dirty: its callers mark the connection once per frame loop.
    // Inlined into consume_input's loop: the call per frame (saved registers, arguments)
    // cost 28 instructions per transaction at FC03 x 10, 9 % of the server's.
    [[gnu::always_inline]] inline bool on_frame(Connection& c, std::uint32_t index,
                                                const codec::TcpFrame& frame) noexcept;
    // The per-frame counters (requests, transactions, bytes queued) summed in tally_ over a
    // frame loop and added to counters_ once at its end: three load-add-store sequences per
    // frame were a twentieth of the server's instructions at FC03 x 10.
    // Also hands the reads answered inline to the model's diagnostics (flush_reads).
    void flush_tally() noexcept;
    // The FC03/04 reads answered by on_frame's shortcut since the last call
    // (slave::read_registers_uncounted), added to the per-function request counters and to
    // the model's diagnostics at once: one atomic add per frame loop, not a locked increment
    // per request. Called before any other request reaches the handler, so its counters and
    // event log see them.
    void flush_reads() noexcept;
    void queue_exception(Connection& c, const codec::TcpFrame& frame,
                         codec::ExceptionCode code) noexcept;
    void hold_from_here(std::uint32_t index, std::int64_t until_ns) noexcept;
    void mark_dirty(Connection& c, std::uint32_t index) noexcept;
    void flush(std::uint32_t index) noexcept;
    void run_timers() noexcept;
    // Output blocks no connection used for a whole interval go back to the heap.
    void trim_output_blocks() noexcept;
    std::size_t blocks_kept() const noexcept;
    std::int64_t next_trim_ns_ = 0;
    std::int64_t next_deadline() const noexcept;

    void lru_unlink(std::uint32_t index) noexcept;
    void lru_push_back(std::uint32_t index) noexcept;
    void touch(std::uint32_t index) noexcept;

    ServerConfig config_;
    slave::DataModel& model_;
    const slave::UnitModels* units_;  // routes by unit id when set
    // MBAP framing, no unit routing, unit filter, outstanding cap or faults: on_frame's
    // shortcut applies (to connections without TLS).
    bool plain_frames_ = false;
    int listen_fd_;
    unsigned index_;
    std::atomic<std::uint32_t>& open_connections_;
    slave::FaultInjector faults_;

    net::EventLoop loop_;
    bool use_buf_ring_ = false;  // receives take provided buffers (a ring, or epoll's pool)
    bool multishot_recv_ = false;
    bool multishot_accept_ = false;
    unsigned table_slots_ = 0;
    bool direct_ = false;  // Connection::fd is a slot of ring_'s file table
    bool ktls_ = false;    // TLS connections are handed to the kernel's TLS after the handshake
    int stop_fd_ = -1;
    std::uint64_t stop_value_ = 0;
    int mail_fd_ = -1;  // eventfd: another worker asked for an eviction
    std::uint64_t mail_value_ = 0;
    bool cross_evict_ = false;  // several workers, a limit, and the evict policy
    std::vector<Worker*> peers_;
    std::atomic<std::int64_t> oldest_idle_ns_{INT64_MAX};  // INT64_MAX: no connection
    std::atomic<std::uint32_t> evict_requests_{0};
    bool stopping_ = false;
    std::int64_t now_ = 0;
    std::int64_t accept_pause_ns_ = 0;  // next pause after EMFILE/ENFILE; reset by an accept
    __kernel_timespec accept_pause_ts_{};

    ConnectionTable conns_;  // stable addresses; grows, never shrinks
    std::vector<std::uint32_t> free_slots_;
    net::DirtyList dirty_;
    std::vector<std::uint32_t> rearm_;
    std::vector<std::uint32_t> held_;
    std::vector<std::uint32_t> partial_;  // connections holding part of a frame
    std::uint32_t lru_head_ = kNoConn;
    std::uint32_t lru_tail_ = kNoConn;
    std::uint32_t open_here_ = 0;
    std::uint32_t handshaking_ = 0;  // open TLS connections whose handshake is not done
    BlockPool pool_;
    std::vector<std::uint16_t> stash_next_;  // per buffer id
    std::vector<std::uint32_t> stash_size_;  // per buffer id

    Link::Kind link_kind_ = Link::Kind::Mbap;  // every connection's transport
    std::vector<std::uint8_t> link_scratch_;   // decrypted input, one record at a time

    ServerCounters counters_;
    struct FrameTally {
        std::uint64_t requests = 0;
        std::uint64_t transactions = 0;
        std::uint64_t pending_output = 0;
        // FC04 and FC03 answered by the shortcut in on_frame, by function code & 1:
        // their per-function request counts and diagnostics (flush_reads()).
        std::uint64_t reads_by_function[2] = {0, 0};
    };
    FrameTally tally_;   // flush_tally()
    Error setup_error_;  // written before init_status_ is set to -1
    std::atomic<int> init_status_{0};
};

}  // namespace mbstorm::server
