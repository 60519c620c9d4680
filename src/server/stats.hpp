// Server counters: each worker thread owns one ServerCounters block and is its only writer;
// anyone may read a snapshot at any time (relaxed atomics, no locks on the hot path).
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <string>

namespace mbstorm::server {

struct ServerStats {
    std::uint64_t transactions = 0;               // requests answered (normal or exception)
    std::uint64_t requests = 0;                   // well-framed requests received
    std::array<std::uint64_t, 256> exceptions{};  // by exception code (fault injection: any)
    std::uint64_t bytes_in = 0;
    std::uint64_t bytes_out = 0;
    std::uint64_t connections_current = 0;
    std::uint64_t connections_total = 0;
    std::uint64_t discarded_frames = 0;    // protocol id != 0
    std::uint64_t bad_framing_closes = 0;  // MBAP length 0, 1 or > 254; RTU frame too long
    // RTU over TCP: frames with a bad CRC, dropped (the link closed only for one with no
    // length rule to find the next frame by)
    std::uint64_t crc_errors = 0;
    std::uint64_t idle_closes = 0;
    std::uint64_t frame_timeouts = 0;  // closed: a started frame did not complete in time
    std::uint64_t evictions = 0;
    std::uint64_t refusals = 0;
    std::uint64_t accept_fd_exhausted = 0;  // accepts failed with EMFILE/ENFILE (then a pause)
    std::uint64_t busy_rejects = 0;         // 06 from the outstanding cap
    std::uint64_t foreign_unit = 0;         // requests for another unit id
    std::uint64_t fault_drops = 0;
    std::uint64_t fault_no_answer = 0;
    std::uint64_t fault_delayed = 0;
    std::uint64_t backpressure_pauses = 0;
    std::uint64_t pending_output = 0;       // bytes queued for sending right now
    std::uint64_t pending_output_peak = 0;  // largest queue one connection ever had
    std::uint64_t output_blocks = 0;        // output blocks allocated (pooled), at the peak
    std::uint64_t output_blocks_held = 0;   // of them, still allocated (idle ones are given back)
    std::uint64_t tls_handshakes = 0;       // --transport tls: handshakes completed
    std::uint64_t tls_resumed = 0;          // of them, sessions resumed
    std::uint64_t tls_refused = 0;          // closed at the handshake (certificate, role, protocol)
    std::uint64_t tls_role_denied = 0;  // requests answered 01: the role may not use the function
    // Of the handshakes, connections handed to the kernel's TLS (the rest stayed in userspace
    // OpenSSL), and offloaded connections ended by a record the kernel does not pass as data
    // (close_notify, an alert, a TLS 1.3 KeyUpdate) or by a hand-off that failed half-way.
    std::uint64_t tls_offloaded = 0;
    std::uint64_t tls_offload_errors = 0;
    std::array<std::uint64_t, 256> requests_by_function{};  // well-framed requests, by code byte

    std::uint64_t exceptions_total() const noexcept;
    ServerStats& operator+=(const ServerStats& o) noexcept;
};

class ServerCounters {
  public:
    enum Id : unsigned {
        Transactions,
        Requests,
        BytesIn,
        BytesOut,
        ConnectionsCurrent,
        ConnectionsTotal,
        DiscardedFrames,
        BadFramingCloses,
        IdleCloses,
        FrameTimeouts,
        Evictions,
        Refusals,
        AcceptFdExhausted,
        BusyRejects,
        ForeignUnit,
        FaultDrops,
        FaultNoAnswer,
        FaultDelayed,
        BackpressurePauses,
        PendingOutput,
        PendingOutputPeak,
        OutputBlocks,
        OutputBlocksHeld,
        CrcErrors,
        TlsHandshakes,
        TlsResumed,
        TlsRefused,
        TlsRoleDenied,
        TlsOffloaded,
        TlsOffloadErrors,
        kCount
    };

    // Single writer: a load and a store, no locked read-modify-write.
    void add(Id id, std::uint64_t n = 1) noexcept {
        auto& c = values_[id];
        c.store(c.load(std::memory_order_relaxed) + n, std::memory_order_relaxed);
    }
    void sub(Id id, std::uint64_t n = 1) noexcept {
        auto& c = values_[id];
        c.store(c.load(std::memory_order_relaxed) - n, std::memory_order_relaxed);
    }
    void set(Id id, std::uint64_t v) noexcept { values_[id].store(v, std::memory_order_relaxed); }
    void set_max(Id id, std::uint64_t v) noexcept {
        auto& c = values_[id];
        if (v > c.load(std::memory_order_relaxed)) c.store(v, std::memory_order_relaxed);
    }
    void add_exception(std::uint8_t code) noexcept {
        auto& c = exceptions_[code];
        c.store(c.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
    }
    void add_request(std::uint8_t function_code, std::uint64_t n = 1) noexcept {
        auto& c = by_function_[function_code];
        c.store(c.load(std::memory_order_relaxed) + n, std::memory_order_relaxed);
    }
    ServerStats snapshot() const noexcept;

  private:
    std::array<std::atomic<std::uint64_t>, kCount> values_{};
    std::array<std::atomic<std::uint64_t>, 256> exceptions_{};
    std::array<std::atomic<std::uint64_t>, 256> by_function_{};
};

// "[  3.0s] tps 123456 conns 64 (total 64) in 1.2 MB/s out 2.9 MB/s exc 0 discarded 0 ..."
std::string format_stats_line(const ServerStats& now, const ServerStats& before, double elapsed_s,
                              double interval_s);
// Multi-line summary for shutdown.
std::string format_summary(const ServerStats& total, double elapsed_s);

}  // namespace mbstorm::server
