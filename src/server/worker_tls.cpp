// The server worker's TLS path (Modbus/TCP Security): ciphertext in from the recv
// completions, plaintext frames on to the same splitter and handler as plain TCP, and the
// output queue's plaintext encrypted just before it is sent.
#include <sys/socket.h>

#include "net/direct_socket.hpp"
#include "net/user_data.hpp"
#include "server/worker.hpp"

namespace mbstorm::server {

void Worker::tls_input(std::uint32_t index, const std::uint8_t* data, std::size_t size) noexcept {
    Connection& c = conns_[index];
    TlsLink& t = *c.tls;
    t.session.feed(data, size);
    if (!t.session.established()) {
        const net::TlsStatus hs = t.session.handshake();
        if (hs == net::TlsStatus::WantMore) {
            // A handshake that stalls holds a TLS session: --frame-timeout bounds it like a
            // frame that stops half-way (counted as a slow frame), timed from the accept.
            if (c.frame_started_ns == 0) start_frame_clock(c, index);
            if (t.session.pending_output() > 0) mark_dirty(c, index);  // our next flight
            return;
        }
        if (hs != net::TlsStatus::Ok) {
            tls_refuse(index);
            return;
        }
        c.frame_started_ns = 0;  // the handshake is done; frames are timed from here on
        --handshaking_;
        counters_.add(ServerCounters::TlsHandshakes);
        if (t.session.resumed()) counters_.add(ServerCounters::TlsResumed);
        t.allowed = config_.tls_roles.allowed_for(t.session.peer_role());
        if (t.evict_when_established) make_room_after_handshake(index);
    }
    for (;;) {
        std::size_t n = 0;
        const net::TlsStatus st = t.session.read(tls_plain_.data(), tls_plain_.size(), n);
        if (n > 0) {
            consume_frames(index, tls_plain_.data(), n);
            if (c.state != Connection::State::Open || c.framing_lost) return;
            continue;
        }
        if (st == net::TlsStatus::Closed) {
            // close_notify: like a half-close, what came before is still answered.
            c.peer_done = true;
            c.frame_started_ns = 0;
            if (c.recv_armed) cancel_recv(index);
        } else if (st == net::TlsStatus::Failed) {
            close_connection(index);
            return;
        }
        break;
    }
    // A record that has not all come is a frame still arriving: --frame-timeout bounds it (every
    // ciphertext byte of a dripped record would otherwise keep the connection alive).
    if (c.frame_started_ns == 0 && t.session.partial_input()) start_frame_clock(c, index);
    if (t.session.pending_output() > 0) mark_dirty(c, index);  // tickets, key updates
    if (ktls_) tls_offload(index);
}

void Worker::tls_offload(std::uint32_t index) noexcept {
    Connection& c = conns_[index];
    TlsLink& t = *c.tls;
    // Only while every byte of ciphertext is in OpenSSL or in the kernel's queue: no recv in
    // flight (single-shot recvs with kTLS: this is the completion of the last one) and none
    // stashed, none of ours unsent (the TLS 1.3 tickets go first), no plaintext half-way
    // through a record.
    if (t.kernel || t.stays_in_userspace || c.state != Connection::State::Open || c.recv_armed ||
        c.stash_head != kNoBuffer || c.send_inflight || t.has_output() || t.plain_carried != 0 ||
        c.peer_done || c.framing_lost)
        return;
    const net::KtlsHandOffResult handed = net::ktls_hand_off(t.session, c.fd, !direct_);
    if (handed == net::KtlsHandOffResult::Later) return;  // the next input tries again
    if (handed != net::KtlsHandOffResult::Done) {
        t.stays_in_userspace = true;
        if (handed == net::KtlsHandOffResult::Broken) {
            ktls_ = false;  // the connections after this one stay in userspace
            counters_.add(ServerCounters::TlsOffloadErrors);
            close_connection(index);
        }
        return;
    }
    t.kernel = true;
    counters_.add(ServerCounters::TlsOffloaded);
}

void Worker::make_room_after_handshake(std::uint32_t index) noexcept {
    conns_[index].tls->evict_when_established = false;
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

void Worker::tls_refuse(std::uint32_t index) noexcept {
    Connection& c = conns_[index];
    counters_.add(ServerCounters::TlsRefused);
    // Read no more; the alert the handshake left goes out, then close_if_answered closes.
    c.framing_lost = true;
    c.frame_started_ns = 0;
    drop_stash(index);
    if (c.tls->session.pending_output() > 0)
        mark_dirty(c, index);
    else
        close_connection(index);
}

void Worker::tls_flush(std::uint32_t index) noexcept {
    Connection& c = conns_[index];
    TlsLink& t = *c.tls;
    if (c.state != Connection::State::Open || c.send_inflight) return;
    if (t.cipher_sent == t.cipher_out.size()) {
        t.cipher_out.clear();
        t.cipher_sent = 0;
        if (t.session.established() && t.plain_carried == 0) {
            std::size_t size = 0;
            const std::uint8_t* p = c.out.sendable(c.hold_pos, size);
            if (p != nullptr && size > 0) {
                if (t.session.write(p, size) != net::TlsStatus::Ok) {
                    close_connection(index);
                    return;
                }
                t.plain_carried = size;
            }
        }
        try {
            t.session.take_output(t.cipher_out);
        } catch (...) {
            close_connection(index);
            return;
        }
        if (t.cipher_out.empty()) return;
    }
    if (!loop_.send(c.fd, t.cipher_out.data() + t.cipher_sent,
                    static_cast<unsigned>(t.cipher_out.size() - t.cipher_sent),
                    net::encode_user_data(Op::Send, index, c.generation)))
        return;
    c.send_inflight = true;
}

std::size_t Worker::tls_sent(TlsLink& t, std::size_t n) noexcept {
    counters_.add(ServerCounters::BytesOut, n);
    t.cipher_sent += n;
    if (t.cipher_sent < t.cipher_out.size()) return 0;
    const std::size_t plain = t.plain_carried;
    t.plain_carried = 0;
    return plain;
}

}  // namespace mbstorm::server
