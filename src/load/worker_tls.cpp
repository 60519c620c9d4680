// The load worker's TLS path (Modbus/TCP Security): the handshake after the TCP connect
// (timed and counted), ciphertext in from the recv completions and plaintext on to the same
// MBAP splitter, and each flush's queued requests encrypted into one record before the send.
#include <sys/socket.h>

#include <algorithm>
#include <cerrno>
#include <chrono>

#include <fmt/format.h>

#include "load/worker.hpp"
#include "net/clock.hpp"
#include "net/direct_socket.hpp"
#include "net/user_data.hpp"

namespace mbstorm::load {

void Worker::tls_begin(std::uint32_t index, std::int64_t now) noexcept {
    Connection& c = connections_[index];
    TlsLink& t = *c.tls;
    t.session.reset();
    t.session.emplace(plan_.tls, plan_.tls_resume ? t.saved : nullptr);
    if (!t.session->valid()) {
        tls_error_ = t.session->error();
        on_connect(index, -EPROTO, now);
        return;
    }
    t.kernel = t.stays_in_userspace = false;
    if (ktls_) {
        try {
            t.session->track_for_offload();
        } catch (...) {
            t.stays_in_userspace = true;  // no memory for the tracker: OpenSSL keeps the records
        }
    }
    c.state = Connection::State::Handshaking;
    t.handshake_started_ns = now;
    c.splitter.reset();
    t.session->handshake();  // the ClientHello
    arm_recv(index);
    tls_pump(index);
}

bool Worker::tls_input(std::uint32_t index, codec::Bytes& data, std::int64_t now) noexcept {
    Connection& c = connections_[index];
    TlsLink& t = *c.tls;
    net::TlsSession& session = *t.session;
    session.feed(data.data(), data.size());
    if (c.state == Connection::State::Handshaking) {
        const net::TlsStatus hs = session.handshake();
        tls_pump(index);
        if (hs == net::TlsStatus::WantMore) return false;
        if (hs != net::TlsStatus::Ok) {
            tls_error_ = session.error();
            on_connect(index, -EPROTO, now);
            return false;
        }
        const auto took =
            static_cast<std::uint64_t>(std::max<std::int64_t>(now - t.handshake_started_ns, 0));
        ++connection_stats.tls_handshakes;
        if (session.resumed()) ++connection_stats.tls_resumed;
        connection_stats.tls_handshake_ns_total += took;
        connection_stats.tls_handshake_ns_max =
            std::max(connection_stats.tls_handshake_ns_max, took);
        if (setup_.live != nullptr) {
            setup_.live->tls_handshakes.add();
            if (session.resumed()) setup_.live->tls_resumed.add();
            setup_.live->tls_handshake_ns.add(took);
        }
        on_connect(index, 0, now);
        if (c.state != Connection::State::Open) return false;
    }
    std::size_t size = 0;
    for (;;) {
        std::size_t n = 0;
        const net::TlsStatus st =
            session.read(tls_plain_.data() + size, tls_plain_.size() - size, n);
        size += n;
        if (n > 0 && size < tls_plain_.size()) continue;
        if (st == net::TlsStatus::Failed && !tls_answered_) {
            tls_refused(session.error());
            close_connection(index, now, stats::Outcome::ConnectionClosed);
            return false;
        }
        if (st == net::TlsStatus::Closed || st == net::TlsStatus::Failed) {
            // close_notify or a record that does not verify: the stream is over.
            ++connection_stats.closed_by_peer;
            if (setup_.live != nullptr) setup_.live->connections_closed_by_peer.add();
            close_connection(index, now, stats::Outcome::ConnectionClosed);
            return false;
        }
        break;
    }
    if (size > 0) tls_answered_ = true;
    tls_pump(index);  // tickets, key updates
    data = codec::Bytes(tls_plain_.data(), size);
    return !ktls_ || tls_offload(index, now);
}

bool Worker::tls_offload(std::uint32_t index, std::int64_t now) noexcept {
    Connection& c = connections_[index];
    TlsLink& t = *c.tls;
    // Only while every byte of ciphertext is in OpenSSL or in the kernel's queue: no recv in
    // flight (single-shot recvs with kTLS: this is the completion of the last one) and no
    // send of ours (its ciphertext must reach the wire before the kernel's records).
    if (t.kernel || t.stays_in_userspace || c.state != Connection::State::Open || c.recv_armed ||
        c.send_in_flight || !t.session)
        return true;
    const net::KtlsHandOffResult handed = net::ktls_hand_off(*t.session, c.fd, !direct_);
    if (handed == net::KtlsHandOffResult::Later) return true;  // the next answer tries again
    if (handed != net::KtlsHandOffResult::Done) {
        t.stays_in_userspace = true;
        if (handed == net::KtlsHandOffResult::Userspace) return true;
        ktls_ = false;  // Broken: the connections after this one stay in userspace
        ++connection_stats.tls_offload_errors;
        if (setup_.live != nullptr) setup_.live->tls_offload_errors.add();
        close_connection(index, now, stats::Outcome::ConnectionClosed);
        return false;
    }
    t.kernel = true;
    ++connection_stats.tls_offloaded;
    if (setup_.live != nullptr) setup_.live->tls_offloaded.add();
    return true;
}

void Worker::tls_refused(const std::string& why) noexcept {
    // TLS 1.3 ends the client's handshake before the server has checked its certificate: a
    // refusal arrives as an alert after it, before any answer. (A close without an alert
    // proves nothing: fault-injecting servers close before answering too.) It is the server's
    // half of a handshake that failed, counted as such.
    ++connection_stats.tls_handshake_failures;
    if (setup_.live != nullptr) setup_.live->tls_handshake_failures.add();
    fatal_error = fmt::format("cannot talk to {}: TLS session refused: {}", setup_.target, why);
    setup_.abort->store(true);
}

void Worker::tls_check_handshake_time(std::uint32_t index, std::int64_t now) noexcept {
    const TlsLink& t = *connections_[index].tls;
    if (now - t.handshake_started_ns < plan_.connect_timeout.count()) return;
    tls_error_ = fmt::format("no handshake within the connect timeout ({}s)",
                             std::chrono::duration<double>(plan_.connect_timeout).count());
    on_connect(index, -EPROTO, now);
}

void Worker::tls_send_queued(std::uint32_t index) noexcept {
    Connection& c = connections_[index];
    if (c.tls->session->write(c.queue_data(), c.queued) != net::TlsStatus::Ok) {
        close_connection(index, net::now_ns(), stats::Outcome::ConnectionClosed);
        return;
    }
    c.queued = 0;
    tls_pump(index);
}

void Worker::tls_pump(std::uint32_t index) noexcept {
    Connection& c = connections_[index];
    TlsLink& t = *c.tls;
    if (c.send_in_flight || c.fd < 0 || !t.session || t.session->pending_output() == 0) return;
    t.cipher.clear();
    try {
        t.session->take_output(t.cipher);
    } catch (...) {
        return;
    }
    // A send that cannot be queued (a broken ring) loses the ciphertext: the connection then
    // times out like any other that stops answering.
    if (!loop_.send(c.fd, t.cipher.data(), static_cast<unsigned>(t.cipher.size()),
                    net::encode_user_data(Op::Send, index, c.generation)))
        return;
    ++inflight_ops_;
    c.inflight_len = static_cast<std::uint32_t>(t.cipher.size());
    c.inflight_done = 0;
    c.send_in_flight = true;
}

void Worker::tls_end(Connection& c) noexcept {
    TlsLink& t = *c.tls;
    if (!t.session) return;
    if (plan_.tls_resume && t.session->established()) {
        if (SSL_SESSION* s = t.session->saved_session()) {
            if (t.saved != nullptr) net::free_tls_session(t.saved);
            t.saved = s;
        }
    }
    t.session.reset();  // the ciphertext buffer stays: a send from it may still be in flight
}

}  // namespace mbstorm::load
