// The server worker's side of its connections' links (link.hpp): a TLS handshake's frame clock
// and its end, a refused set-up, a peer's close_notify or broken record, lost framing, the
// link's own output, and handing a TLS link's record layer to the kernel.
#include "server/worker.hpp"

namespace mbstorm::server {

bool Worker::on_link_event(std::uint32_t index, LinkInput event) noexcept {
    Connection& c = conns_[index];
    switch (event) {
        case LinkInput::Drained:
            return true;
        case LinkInput::Stopped:
            return false;
        case LinkInput::SettingUp:
            // A handshake that stalls holds a TLS session: --frame-timeout bounds it like a
            // frame that stops half-way (counted as a slow frame), timed from the accept.
            if (c.frame_started_ns == 0) start_frame_clock(c, index);
            if (c.link.has_own_output()) mark_dirty(c, index);  // our next flight
            return false;
        case LinkInput::SetUpFailed:
            link_refused(index);
            return false;
        case LinkInput::PeerClosed:
            // close_notify: like a half-close, what came before is still answered.
            c.peer_done = true;
            c.frame_started_ns = 0;
            if (c.recv_armed) cancel_recv(index);
            return true;
        case LinkInput::PeerFailed:
            close_connection(index);
            return false;
        case LinkInput::FramingLost:
            // The frames before it are answered; the connection closes after that.
            lose_framing(index);
            return false;
        case LinkInput::BadCrc:
            lose_framing(index, /*crc=*/true);
            return false;
    }
    return false;
}

void Worker::on_link_set_up(std::uint32_t index) noexcept {
    Connection& c = conns_[index];
    c.frame_started_ns = 0;  // the handshake is done; frames are timed from here on
    --handshaking_;
    counters_.add(ServerCounters::TlsHandshakes);
    if (c.link.resumed()) counters_.add(ServerCounters::TlsResumed);
    if (c.evict_when_set_up) make_room_after_handshake(index);
}

void Worker::after_link_input(std::uint32_t index) noexcept {
    Connection& c = conns_[index];
    // A record that has not all come is a frame still arriving: --frame-timeout bounds it (every
    // ciphertext byte of a dripped record would otherwise keep the connection alive).
    if (c.frame_started_ns == 0 && c.link.record_partly_in()) start_frame_clock(c, index);
    if (c.link.has_own_output()) mark_dirty(c, index);  // tickets, key updates
    if (ktls_) try_hand_off(index);
}

void Worker::try_hand_off(std::uint32_t index) noexcept {
    Connection& c = conns_[index];
    // Only while every byte of ciphertext is in OpenSSL or in the kernel's queue: no recv in
    // flight (single-shot recvs with kTLS: this is the completion of the last one) and none
    // stashed, none of ours unsent (the TLS 1.3 tickets go first), no plaintext half-way
    // through a record (the link's part of the check).
    if (c.state != Connection::State::Open || c.recv_armed || c.stash_head != kNoBuffer ||
        c.send_inflight || c.peer_done || c.framing_lost || !c.link.may_hand_off())
        return;
    switch (c.link.hand_off(c.fd, !direct_)) {
        case net::KtlsHandOffResult::Later:  // the next input tries again
        case net::KtlsHandOffResult::Userspace:
            return;
        case net::KtlsHandOffResult::Done:
            counters_.add(ServerCounters::TlsOffloaded);
            return;
        case net::KtlsHandOffResult::Broken:
            ktls_ = false;  // the connections after this one stay in userspace
            counters_.add(ServerCounters::TlsOffloadErrors);
            close_connection(index);
            return;
    }
}

void Worker::make_room_after_handshake(std::uint32_t index) noexcept {
    conns_[index].evict_when_set_up = false;
    if (open_connections_.load(std::memory_order_relaxed) <= config_.max_connections) return;
    if (cross_evict_) {
        evict_server_wide_oldest();
        return;
    }
    const std::uint32_t victim = eviction_victim();
    if (victim == kNoConn || victim == index) return;
    counters_.add(ServerCounters::Evictions);
    close_connection(victim);
}

void Worker::link_refused(std::uint32_t index) noexcept {
    Connection& c = conns_[index];
    counters_.add(ServerCounters::TlsRefused);
    // Read no more; the alert the handshake left goes out, then close_if_answered closes.
    c.framing_lost = true;
    c.frame_started_ns = 0;
    drop_stash(index);
    if (c.link.has_own_output())
        mark_dirty(c, index);
    else
        close_connection(index);
}

}  // namespace mbstorm::server
