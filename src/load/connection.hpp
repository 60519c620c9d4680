// One client connection of a worker: socket state, its outstanding transactions, its link (how
// its bytes become answers and its requests bytes: link.hpp), and a double send buffer (one
// half being sent by the kernel, the other collecting the requests of the current loop
// iteration).
#pragma once

#include <cstdint>
#include <memory>
#include <utility>

#include "load/link.hpp"
#include "load/transaction_table.hpp"

namespace mbstorm::load {

struct Connection {
    enum class State : std::uint8_t { Waiting, Connecting, Handshaking, Open };

    Connection(std::uint32_t depth, std::uint32_t send_half_bytes, std::uint16_t first_id,
               Link link_of_run)
        : table(depth, first_id),
          link(std::move(link_of_run)),
          send_buffer(std::make_unique<std::uint8_t[]>(2ull * send_half_bytes)),
          send_half(send_half_bytes) {}

    std::uint8_t* queue_data() noexcept { return send_buffer.get() + queue_half * send_half; }
    std::uint8_t* inflight_data() noexcept {
        return send_buffer.get() + (queue_half ^ 1u) * send_half;
    }

    State state = State::Waiting;
    int fd = -1;  // a descriptor, or with direct descriptors the slot in the ring's table
    bool slot_closing = false;     // direct: the slot's close has not completed yet
    std::uint32_t generation = 0;  // bumped on close: completions of older sockets are ignored
    TransactionTable table;
    Link link;

    std::unique_ptr<std::uint8_t[]> send_buffer;
    std::uint32_t send_half;
    std::uint32_t queued = 0;  // bytes waiting in the queue half
    std::uint32_t queue_half = 0;
    const std::uint8_t* inflight_base = nullptr;  // what the send in flight sends
    std::uint32_t inflight_len = 0;
    std::uint32_t inflight_done = 0;
    bool send_in_flight = false;  // one send at a time per connection, whatever its generation
    bool recv_armed = false;
    bool dirty = false;     // in the worker's flush list
    bool in_ready = false;  // open loop: in the worker's ready queue
    bool ever_opened = false;
    bool connect_queued = false;  // in the worker's connect heap

    // One past the newest transaction sequence answered: an older one that times out was
    // skipped by the target (see stats::PipeliningSigns).
    std::uint64_t answered_up_to = 0;

    std::int64_t backoff_ns = 0;
    // --source-addr: how far past its own port this connection's next bind starts (grows by
    // the probes tried each time a connect fails with EADDRNOTAVAIL).
    std::uint32_t port_shift = 0;
    std::int64_t connect_started_ns = 0;
};

}  // namespace mbstorm::load
