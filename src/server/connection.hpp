// One accepted connection's state. Kept small and fixed: input lives in the thread's shared
// buffer ring (a partial frame in the splitter's 260 bytes), output blocks are pooled and
// held only while there is output.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>

#include "server/link.hpp"
#include "server/out_queue.hpp"

namespace mbstorm::server {

inline constexpr std::uint32_t kNoConn = std::numeric_limits<std::uint32_t>::max();
inline constexpr std::uint16_t kNoBuffer = 0xFFFF;
inline constexpr std::uint64_t kNoHold = std::numeric_limits<std::uint64_t>::max();

struct Connection {
    enum class State : std::uint8_t { Free, Open, Closing };

    int fd = -1;
    std::uint32_t generation = 0;
    State state = State::Free;
    bool recv_armed = false;     // a recv (multishot or single) is in the kernel
    bool send_inflight = false;  // a send is in the kernel (its block must stay put)
    bool paused = false;         // backpressure: not reading until output drains
    bool dirty = false;          // has new output, queued for the end-of-batch flush
    bool in_hold_list = false;
    // The input is over: the peer half-closed (its stashed input is still served) or framing
    // was lost (what follows is discarded). Once the answers have gone out, the connection closes.
    bool peer_done = false;
    bool framing_lost = false;
    bool in_partial_list = false;
    // Admitted one over the connection limit when every connection held had authenticated:
    // the oldest idle one is evicted only once this link's set-up (TLS handshake) succeeds.
    bool evict_when_set_up = false;

    // LRU list of open connections (least recently active at the head), for idle timeouts
    // and "evict the oldest idle connection".
    std::uint32_t lru_prev = kNoConn;
    std::uint32_t lru_next = kNoConn;
    std::int64_t last_active_ns = 0;
    // When the frame the splitter holds in part began to arrive (0: none); a frame must be
    // complete within the frame timeout, however slowly its bytes drip in.
    std::int64_t frame_started_ns = 0;

    // Output from stream position hold_pos on waits until hold_until_ns (delay/stall faults).
    std::uint64_t hold_pos = kNoHold;
    std::int64_t hold_until_ns = 0;
    // Responses queued since the output queue was last empty (outstanding-transaction cap).
    std::uint32_t unanswered = 0;
    // Buffer-ring buffers received while paused, in arrival order (linked through the
    // worker's per-buffer table): a multishot recv may deliver a burst before its cancel lands.
    std::uint16_t stash_head = kNoBuffer;
    std::uint16_t stash_tail = kNoBuffer;

    OutQueue out;
    std::unique_ptr<std::uint8_t[]> plain_buf;  // only without a buffer ring
    Link link;  // how its bytes become requests and its answers bytes (link.hpp)
};

}  // namespace mbstorm::server
