// The load worker's side of its connections' links (link.hpp): what it does when a link is set
// up, fails, is closed by the peer or loses its framing, the bytes a link itself has to send,
// and handing a TLS link's record layer to the kernel.
#include <algorithm>
#include <chrono>

#include <fmt/format.h>

#include "load/worker.hpp"
#include "net/clock.hpp"

namespace mbstorm::load {

bool Worker::on_link_event(std::uint32_t index, LinkInput event, std::int64_t now) noexcept {
    Connection& c = connections_[index];
    switch (event) {
        case LinkInput::Answers:
            return true;
        case LinkInput::SettingUp:
            send_link_output(index);
            if (!c.recv_armed) arm_recv(index);
            return false;
        case LinkInput::SetUp:
            send_link_output(index);  // the handshake's last message goes before any request
            count_set_up(c.link);
            on_connect(index, 0, now);
            return c.state == Connection::State::Open;
        case LinkInput::SetUpFailed:
            link_error_ = c.link.error();
            on_connect(index, kLinkSetUpFailed, now);
            return false;
        case LinkInput::PeerFailed:
            if (!links_answered_)
                links_answered_ =
                    std::any_of(connections_.begin(), connections_.end(),
                                [](const Connection& o) { return o.link.carried_data(); });
            if (!links_answered_) {
                link_refused(c.link.error());
                close_connection(index, now, stats::Outcome::ConnectionClosed);
                return false;
            }
            [[fallthrough]];  // a record that does not verify ends the stream like a close
        case LinkInput::PeerClosed:
            ++connection_stats.closed_by_peer;
            if (setup_.live != nullptr) setup_.live->connections_closed_by_peer.add();
            close_connection(index, now, stats::Outcome::ConnectionClosed);
            return false;
        case LinkInput::FramingLost:
            // The stream cannot be resynchronised: count it and start a fresh connection. The
            // transactions it carried end as framing errors, not as a peer's close.
            ++framing_errors;
            close_connection(index, now, stats::Outcome::FramingError);
            return false;
        case LinkInput::BadCrc:
            // No reliable frame boundary after a bad CRC: the transactions the connection
            // carried end with it, and a fresh one starts.
            ++crc_errors;
            close_connection(index, now, stats::Outcome::CrcError);
            return false;
    }
    return false;
}

void Worker::count_set_up(const Link& link) noexcept {
    const std::uint64_t took = link.set_up_ns();
    ++connection_stats.tls_handshakes;
    if (link.resumed()) ++connection_stats.tls_resumed;
    connection_stats.tls_handshake_ns_total += took;
    connection_stats.tls_handshake_ns_max = std::max(connection_stats.tls_handshake_ns_max, took);
    if (setup_.live != nullptr) {
        setup_.live->tls_handshakes.add();
        if (link.resumed()) setup_.live->tls_resumed.add();
        setup_.live->tls_handshake_ns.add(took);
    }
}

void Worker::send_link_bytes(std::uint32_t index) noexcept {
    Connection& c = connections_[index];
    if (c.send_in_flight || c.fd < 0) return;
    // A send that cannot be queued (a broken ring) loses these bytes: the connection then
    // times out like any other that stops answering.
    if (const codec::Bytes wire = c.link.take_output(); !wire.empty()) start_send(index, wire);
}

bool Worker::hand_off_now(std::uint32_t index, std::int64_t now) noexcept {
    Connection& c = connections_[index];
    // Only while every byte of ciphertext is in OpenSSL or in the kernel's queue: no recv in
    // flight (single-shot recvs with kTLS: this is the completion of the last one) and no
    // send of ours (its ciphertext must reach the wire before the kernel's records).
    if (c.state != Connection::State::Open || c.recv_armed || c.send_in_flight ||
        !c.link.may_hand_off())
        return true;
    switch (c.link.hand_off(c.fd, !direct_)) {
        case net::KtlsHandOffResult::Later:  // the next answer tries again
        case net::KtlsHandOffResult::Userspace:
            return true;
        case net::KtlsHandOffResult::Done:
            ++connection_stats.tls_offloaded;
            if (setup_.live != nullptr) setup_.live->tls_offloaded.add();
            return true;
        case net::KtlsHandOffResult::Broken:
            ktls_ = false;  // the connections after this one stay in userspace
            ++connection_stats.tls_offload_errors;
            if (setup_.live != nullptr) setup_.live->tls_offload_errors.add();
            close_connection(index, now, stats::Outcome::ConnectionClosed);
            return false;
    }
    return true;
}

void Worker::link_refused(const std::string& why) noexcept {
    // TLS 1.3 ends the client's handshake before the server has checked its certificate: a
    // refusal arrives as an alert after it, before any answer. (A close without an alert
    // proves nothing: fault-injecting servers close before answering too.) It is the server's
    // half of a handshake that failed, counted as such.
    ++connection_stats.tls_handshake_failures;
    if (setup_.live != nullptr) setup_.live->tls_handshake_failures.add();
    fatal_error =
        Error(ErrorCode::Network,
              fmt::format("cannot talk to {}: TLS session refused: {}", setup_.target, why));
    setup_.abort->store(true);
}

void Worker::check_set_up_time(std::uint32_t index, std::int64_t now) noexcept {
    if (!connections_[index].link.set_up_overdue(now, plan_.connect_timeout.count())) return;
    link_error_ = fmt::format("no handshake within the connect timeout ({}s)",
                              std::chrono::duration<double>(plan_.connect_timeout).count());
    on_connect(index, kLinkSetUpFailed, now);
}

}  // namespace mbstorm::load
