#include "server/stats.hpp"

#include <fmt/format.h>

namespace mbstorm::server {

std::uint64_t ServerStats::exceptions_total() const noexcept {
    std::uint64_t sum = 0;
    for (auto v : exceptions) sum += v;
    return sum;
}

ServerStats& ServerStats::operator+=(const ServerStats& o) noexcept {
    transactions += o.transactions;
    requests += o.requests;
    for (std::size_t i = 0; i < exceptions.size(); ++i) exceptions[i] += o.exceptions[i];
    bytes_in += o.bytes_in;
    bytes_out += o.bytes_out;
    connections_current += o.connections_current;
    connections_total += o.connections_total;
    discarded_frames += o.discarded_frames;
    bad_framing_closes += o.bad_framing_closes;
    crc_errors += o.crc_errors;
    idle_closes += o.idle_closes;
    frame_timeouts += o.frame_timeouts;
    evictions += o.evictions;
    refusals += o.refusals;
    accept_fd_exhausted += o.accept_fd_exhausted;
    busy_rejects += o.busy_rejects;
    foreign_unit += o.foreign_unit;
    fault_drops += o.fault_drops;
    fault_no_answer += o.fault_no_answer;
    fault_delayed += o.fault_delayed;
    backpressure_pauses += o.backpressure_pauses;
    pending_output += o.pending_output;
    if (o.pending_output_peak > pending_output_peak) pending_output_peak = o.pending_output_peak;
    output_blocks += o.output_blocks;
    output_blocks_held += o.output_blocks_held;
    tls_handshakes += o.tls_handshakes;
    tls_resumed += o.tls_resumed;
    tls_refused += o.tls_refused;
    tls_role_denied += o.tls_role_denied;
    tls_offloaded += o.tls_offloaded;
    tls_offload_errors += o.tls_offload_errors;
    for (std::size_t i = 0; i < requests_by_function.size(); ++i)
        requests_by_function[i] += o.requests_by_function[i];
    return *this;
}

ServerStats ServerCounters::snapshot() const noexcept {
    auto v = [this](Id id) { return values_[id].load(std::memory_order_relaxed); };
    ServerStats s;
    s.transactions = v(Transactions);
    s.requests = v(Requests);
    for (std::size_t i = 0; i < exceptions_.size(); ++i)
        s.exceptions[i] = exceptions_[i].load(std::memory_order_relaxed);
    s.bytes_in = v(BytesIn);
    s.bytes_out = v(BytesOut);
    s.connections_current = v(ConnectionsCurrent);
    s.connections_total = v(ConnectionsTotal);
    s.discarded_frames = v(DiscardedFrames);
    s.bad_framing_closes = v(BadFramingCloses);
    s.crc_errors = v(CrcErrors);
    s.idle_closes = v(IdleCloses);
    s.frame_timeouts = v(FrameTimeouts);
    s.evictions = v(Evictions);
    s.refusals = v(Refusals);
    s.accept_fd_exhausted = v(AcceptFdExhausted);
    s.busy_rejects = v(BusyRejects);
    s.foreign_unit = v(ForeignUnit);
    s.fault_drops = v(FaultDrops);
    s.fault_no_answer = v(FaultNoAnswer);
    s.fault_delayed = v(FaultDelayed);
    s.backpressure_pauses = v(BackpressurePauses);
    s.pending_output = v(PendingOutput);
    s.pending_output_peak = v(PendingOutputPeak);
    s.output_blocks = v(OutputBlocks);
    s.output_blocks_held = v(OutputBlocksHeld);
    s.tls_handshakes = v(TlsHandshakes);
    s.tls_resumed = v(TlsResumed);
    s.tls_refused = v(TlsRefused);
    s.tls_role_denied = v(TlsRoleDenied);
    s.tls_offloaded = v(TlsOffloaded);
    s.tls_offload_errors = v(TlsOffloadErrors);
    for (std::size_t i = 0; i < by_function_.size(); ++i)
        s.requests_by_function[i] = by_function_[i].load(std::memory_order_relaxed);
    return s;
}

namespace {

std::string exceptions_text(const ServerStats& s) {
    std::string out;
    for (std::size_t code = 1; code < s.exceptions.size(); ++code) {
        if (s.exceptions[code] == 0) continue;
        out += fmt::format("{}{:02X}:{}", out.empty() ? "" : " ", code, s.exceptions[code]);
    }
    return out.empty() ? "none" : out;
}

}  // namespace

std::string format_stats_line(const ServerStats& now, const ServerStats& before, double elapsed_s,
                              double interval_s) {
    const double dt = interval_s > 0 ? interval_s : 1.0;
    return fmt::format(
        "[{:7.1f}s] tps {:.0f} conns {} (total {}) in {:.2f} MB/s out {:.2f} MB/s exc {} "
        "discarded {} bad-framing {} idle {} slow-frame {} evicted {} refused {} out-of-fds {} "
        "pending {} B",
        elapsed_s, static_cast<double>(now.transactions - before.transactions) / dt,
        now.connections_current, now.connections_total,
        static_cast<double>(now.bytes_in - before.bytes_in) / dt / 1e6,
        static_cast<double>(now.bytes_out - before.bytes_out) / dt / 1e6,
        now.exceptions_total() - before.exceptions_total(), now.discarded_frames,
        now.bad_framing_closes, now.idle_closes, now.frame_timeouts, now.evictions, now.refusals,
        now.accept_fd_exhausted, now.pending_output);
}

std::string format_summary(const ServerStats& t, double elapsed_s) {
    const double secs = elapsed_s > 0 ? elapsed_s : 1.0;
    return fmt::format(
               "summary: {:.1f}s, {} transactions ({:.0f}/s), {} requests\n"
               "  connections: {} total, {} open, {} idle-closed, {} closed for a slow frame, {} "
               "evicted, {} refused, {} accepts out of fds (EMFILE/ENFILE)\n"
               "  bytes: {} in, {} out\n"
               "  exceptions: {} ({})\n"
               "  framing: {} discarded (protocol id != 0), {} closed for bad length, {} with a "
               "bad "
               "CRC (dropped)\n"
               "  emulation: {} busy (06), {} other-unit requests\n"
               "  faults: {} delayed, {} dropped connections, {} unanswered\n"
               "  backpressure: {} pauses, peak queue {} B on one connection, {} output blocks at "
               "the peak ({} held at the end)\n",
               elapsed_s, t.transactions, static_cast<double>(t.transactions) / secs, t.requests,
               t.connections_total, t.connections_current, t.idle_closes, t.frame_timeouts,
               t.evictions, t.refusals, t.accept_fd_exhausted, t.bytes_in, t.bytes_out,
               t.exceptions_total(), exceptions_text(t), t.discarded_frames, t.bad_framing_closes,
               t.crc_errors, t.busy_rejects, t.foreign_unit, t.fault_delayed, t.fault_drops,
               t.fault_no_answer, t.backpressure_pauses, t.pending_output_peak, t.output_blocks,
               t.output_blocks_held) +
           (t.tls_handshakes + t.tls_refused == 0
                ? std::string()
                : fmt::format("  tls: {} handshakes ({} resumed), {} refused at the handshake, {} "
                              "requests denied to their role (01); records by the kernel on {} "
                              "connections ({} ended by a non-data record), userspace OpenSSL "
                              "on {}\n",
                              t.tls_handshakes, t.tls_resumed, t.tls_refused, t.tls_role_denied,
                              t.tls_offloaded, t.tls_offload_errors,
                              t.tls_handshakes - t.tls_offloaded));
}

}  // namespace mbstorm::server
