// Settings of the io_uring Modbus TCP reference slave. Everything optional is off by default.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "codec/framing.hpp"
#include "net/backend.hpp"
#include "slave/faults.hpp"

#include "slave/simulator.hpp"

#include "net/tls_context.hpp"
#include "server/tls_roles.hpp"

namespace mbstorm::slave {
class DataModel;
class UnitModels;
}  // namespace mbstorm::slave

namespace mbstorm::server {

enum class FullPolicy : std::uint8_t {
    EvictOldestIdle,  // close the least recently active connection to admit the new one
    Refuse,           // close the new connection at once
};

enum class ForeignUnitPolicy : std::uint8_t {
    NoAnswer,          // like a device on a bus that is not addressed
    GatewayException,  // exception 0B, as a gateway whose target does not answer
};

struct ServerConfig {
    std::string listen = "127.0.0.1:5020";  // port 0: ephemeral (see Server::port())
    // Mbap: Modbus TCP. Rtu: RTU over TCP (address, PDU, CRC; no MBAP), as gateways speak.
    codec::Framing framing = codec::Framing::Mbap;
    std::uint16_t default_port = 502;  // when `listen` names none (TLS: 802)
    unsigned threads = 0;              // 0: one per core

    std::uint32_t max_connections = 16384;  // across all threads; 0: unlimited
    FullPolicy full_policy = FullPolicy::EvictOldestIdle;
    // Raise RLIMIT_NOFILE towards max_connections at start. Whether raised or not, a
    // descriptor limit below what max_connections needs lowers the effective connection
    // limit (see Server::warning()), so that eviction or refusal happens before accepts fail.
    bool raise_nofile_limit = true;
    std::uint64_t idle_timeout_ms = 0;  // 0: never close idle connections
    // A frame whose first bytes arrived must be complete within this time (a slow drip resets
    // the idle timer with every byte, this does not). 0: no bound.
    std::uint64_t frame_timeout_ms = 10000;

    // Backpressure: stop reading a connection while this much output waits to be sent.
    std::size_t max_pending_output = 64 * 1024;
    // SO_SNDBUF for accepted sockets; 0: the kernel's autotuning (which may hold megabytes).
    int socket_send_buffer = 0;

    // Device emulation (NumberMaxOfServerTransaction): requests beyond this many unanswered
    // ones on a connection get exception 06. 0: no cap.
    unsigned max_outstanding = 0;
    // Answer only this unit id; others per `foreign_unit`.
    std::optional<std::uint8_t> only_unit;
    ForeignUnitPolicy foreign_unit = ForeignUnitPolicy::NoAnswer;

    slave::FaultConfig faults;

    // Modbus/TCP Security: set, every connection is TLS (mutual authentication) with MBAP
    // inside, and requests are checked against the client's role.
    std::shared_ptr<net::TlsContext> tls;
    TlsRoles tls_roles;

    // The shared data model; nullptr: the server owns a default one.
    slave::DataModel* model = nullptr;
    // Per-unit (or shared) models from a device description; takes precedence over `model`.
    // Requests are routed by unit id, and unknown units follow the models' policy.
    const slave::UnitModels* units = nullptr;
    // Simulated inputs (ramps, sines, counters) written into `units` every
    // `simulate_interval_ms` by one background thread. Needs `units`.
    std::vector<slave::SimulatedInput> simulated;
    std::uint32_t simulate_interval_ms = 50;

    // I/O tuning (and switches to force the fallbacks in tests).
    bool use_buf_ring = true;        // provided buffer ring for input, else per-connection buffers
    bool use_multishot_recv = true;  // needs use_buf_ring
    bool use_multishot_accept = true;
    // Accepted sockets as io_uring direct descriptors when the kernel has them: the open-files
    // limit then caps each thread's share of the connections (a ring's table), not their sum.
    bool use_direct_descriptors = true;
    // io_uring, epoll, or io_uring where the process may use it (auto). Server::start sets
    // `backend` from it.
    net::BackendChoice backend_choice = net::BackendChoice::Auto;
    net::Backend backend = net::Backend::IoUring;
    unsigned ring_entries = 4096;
    unsigned buf_ring_count = 2048;  // per thread, power of two
    unsigned buf_size = 4096;
    // Output blocks (16 KiB each) allocated per thread at start; more are added on demand.
    unsigned prealloc_output_blocks = 32;
};

}  // namespace mbstorm::server
