// Runs one case on its own fresh connection(s) and judges it: the slow, exact path. Every
// finding is confirmed here, replay uses it, and so does minimisation. Records the exact bytes
// sent and received per connection with their timing.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "net/socket.hpp"
#include "netfuzz/case.hpp"
#include "netfuzz/link.hpp"
#include "netfuzz/oracle.hpp"

namespace mbstorm::netfuzz {

enum class TraceKind : std::uint8_t {
    Connect,
    ConnectFailed,
    Send,
    Recv,
    ShutdownWrite,
    PeerClosed,
    Reset,
    Timeout,
    Flood,
    FreshProbe,
    LeftUnread,  // a piece the target had not read when the next one was due
};
std::string_view trace_kind_name(TraceKind k) noexcept;
bool trace_kind_from_name(std::string_view name, TraceKind& out) noexcept;

// The connection number trace events of the fresh liveness probe carry.
inline constexpr std::uint8_t kFreshConn = 255;

struct TraceEvent {
    std::int64_t t_us = 0;  // since the case started
    std::uint8_t conn = 0;  // kFreshConn: the fresh liveness-probe connection
    TraceKind kind = TraceKind::Send;
    std::vector<std::uint8_t> bytes;
    std::string note;
};

class DeathWatch;
class StateMarker;

struct ExecOptions {
    int timeout_ms = 1000;  // answer timeout (hang oracle)
    StateRange state;       // where read-after-write is checked
    // Armed sentinels (netfuzz/death_watch.hpp): the target's process died during the case
    // when they all drop, even if a supervisor had it back before the fresh probe. Null: none.
    DeathWatch* watch = nullptr;
    // Where there are no sentinels: a marker register (netfuzz/state_marker.hpp) found back at
    // its initial value after a case that broke a connection is a restart. Null: none.
    StateMarker* marker = nullptr;
    // After the target has read a piece of a frame, how long it gets to act on it before the
    // next piece goes out (replay is patient so that a finding reproduces on a loaded host;
    // the campaign is fast).
    int piece_settle_ms = 0;
    // RTU/ASCII (no transaction ids): how long a frame that may or must get no answer is
    // watched for a late one before the next frame goes out; 0: the answer timeout. The
    // campaign shortens it from the slowest answer it has seen (Execution::slowest_answer_ns).
    int silence_watch_ms = 0;
    // --target-cmd (mbstorm started the target): whether its process has exited. A death on any
    // transport, a serial line included, where no sentinel connection can tell. Empty: the
    // process is not mbstorm's.
    std::function<bool()> process_exited;
};

struct Execution {
    Verdict verdict;
    std::vector<TraceEvent> trace;
    bool down_before = false;  // the very first connect failed: the target was already down
    bool target_down = false;  // the fresh probe after the case could not connect
    std::int64_t slowest_answer_ns = 0;  // of the answers matched to the case's requests
};

Execution execute_case(const Case& c, Connector& target, const TargetProfile& profile,
                       const ExecOptions& options);

enum class ProbeResult : std::uint8_t { Ok, ConnectFailed, NoAnswer, Closed, BadAnswer };
std::string_view probe_result_name(ProbeResult r) noexcept;

// One liveness probe on a fresh connection: connect, send the profile's probe, await it.
ProbeResult probe_target(Connector& target, const TargetProfile& profile, int timeout_ms);

// What a fresh connection's probe result says about the whole server: crash (refuses or
// closes new connections), hang (accepts but does not answer properly), nothing for Ok.
Verdict fresh_probe_verdict(ProbeResult r);

// Connects with a timeout; returns a connected non-blocking fd (TCP_NODELAY) or -errno.
int connect_with_timeout(const net::Endpoint& target, int timeout_ms) noexcept;

// Builds a probe ADU with the given transaction id.
std::vector<std::uint8_t> probe_frame(const TargetProfile& profile, std::uint16_t tid);

}  // namespace mbstorm::netfuzz
