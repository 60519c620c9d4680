// How a load connection's received bytes become answers and its requests become bytes to send,
// chosen once per run: plain MBAP, RTU over TCP, or Modbus/TCP Security (TLS over memory BIOs
// in userspace, handed to the kernel's TLS once it can take the records). The worker moves
// bytes between the socket and its link and reacts to what the link says; it never asks which
// link it has (wrk's `struct sock`). A plain MBAP link pays one predictable branch per receive
// and per send, not a call per frame: the worker pulls answers from its splitter inline.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "codec/bytes.hpp"
#include "codec/framing.hpp"
#include "codec/mbap.hpp"
#include "codec/rtu.hpp"
#include "codec/rtu_stream.hpp"
#include "net/ktls_offload.hpp"
#include "net/tls_session.hpp"

namespace mbstorm::load {

// What a link made of received bytes, besides the answers read from it.
enum class LinkInput : std::uint8_t {
    Answers,      // answers to read (or all read); a partial one waits for more bytes
    SettingUp,    // the link's own set-up (a TLS handshake) took the bytes; its reply waits
    SetUp,        // the set-up finished with these bytes (answers after it to read)
    SetUpFailed,  // the set-up was refused or malformed: error() says why
    PeerFailed,   // the peer broke the session (an alert, a record that does not verify)
    PeerClosed,   // the peer ended the session (close_notify)
    FramingLost,  // no frame boundary can be found again
    BadCrc,       // an answer with a bad CRC: nothing after it is known to be aligned
};

// What connected() did.
enum class LinkStart : std::uint8_t {
    Open,         // requests may go now
    SettingUp,    // a set-up exchange started: its first bytes wait in take_output()
    SetUpFailed,  // the set-up could not start: error() says why
};

class Link {
  public:
    enum class Kind : std::uint8_t { Mbap, Rtu, Tls };

    // tls: the client context (Kind::Tls only); resume: offer the last session on reconnect.
    Link(Kind kind, std::shared_ptr<net::TlsContext> tls = nullptr, bool resume = false);
    Link(Link&&) noexcept;
    Link& operator=(Link&&) noexcept;
    ~Link();

    // The socket is connected. `offload`: track the session for the kernel's TLS.
    LinkStart connected(std::int64_t now, bool offload);
    // The socket is gone: framing starts afresh; a TLS session is kept to be resumed.
    void closed() noexcept;
    // The set-up exchange has taken `timeout_ns` or longer.
    bool set_up_overdue(std::int64_t now, std::int64_t timeout_ns) const noexcept;

    // Received bytes, taken in: Answers (or SetUp, a set-up just finished) when answers may
    // follow from next_answer(); anything else says what the bytes did instead. `scratch` holds
    // decrypted bytes (a TLS link's; shared by the worker's links); `plain` is what the
    // splitter was fed (the received bytes themselves but on a TLS link in userspace).
    LinkInput take(codec::Bytes received, std::int64_t now, std::vector<std::uint8_t>& scratch,
                   codec::Bytes& plain) {
        plain = received;
        switch (kind_) {
            case Kind::Mbap:
                mbap_.feed(received);
                return LinkInput::Answers;
            case Kind::Rtu:
                rtu_->feed(received);
                return LinkInput::Answers;
            case Kind::Tls:
                break;
        }
        const LinkInput opened = open_tls(received, now, scratch, plain);
        if (opened == LinkInput::Answers || opened == LinkInput::SetUp) mbap_.feed(plain);
        return opened;
    }
    // The next whole answer of the bytes taken: true with `frame` set. False when none is
    // left, `end` saying why: Answers (a partial one waits for more bytes), FramingLost (no
    // frame boundary can be found again) or BadCrc. MBAP frames with a wrong protocol id are
    // counted in bad_protocol and skipped.
    // Inline, pulled by the worker's own loop: the answer's handling stays in the receive
    // handler with its locals in registers, as before the link (handing each frame to a
    // callback cost a call or a closure's loads per answer: about 20 instructions, 2-3 % on
    // epoll at 16 x 16).
    [[gnu::always_inline]] bool next_answer(codec::TcpFrame& frame, std::uint64_t& bad_protocol,
                                            LinkInput& end) noexcept {
        for (;;) {
            switch (mbap_.next(frame)) {
                case codec::MbapSplitter::Status::Frame:
                    return true;
                case codec::MbapSplitter::Status::BadProtocolId:
                    ++bad_protocol;
                    continue;
                case codec::MbapSplitter::Status::NeedMore:
                    // An RTU link feeds no MBAP splitter: asked here, once its (empty) MBAP
                    // splitter is done, the kind costs the plain path nothing per answer.
                    if (kind_ == Kind::Rtu) [[unlikely]]
                        return next_rtu_answer(frame, end);
                    end = LinkInput::Answers;
                    return false;
                case codec::MbapSplitter::Status::Fatal:
                    end = LinkInput::FramingLost;
                    return false;
            }
        }
    }

    // A request encoded as MBAP at `at` (`size` bytes, transaction id `id`), rewritten in place
    // as this link frames requests; returns its new size.
    std::size_t frame_request(std::uint8_t* at, std::size_t size, std::uint16_t id) noexcept {
        if (kind_ != Kind::Rtu) return size;
        rtu_transaction_ = id;  // answers carry none: the next one is this request's
        return codec::mbap_to_rtu_in_place(at, size);
    }
    // The bytes that carry `size` queued request bytes at `queued`: those bytes themselves, or
    // the link's own ciphertext of them. False when the link failed.
    bool seal(const std::uint8_t* queued, std::size_t size, codec::Bytes& wire) noexcept {
        if (bytes_pass_through_) {
            wire = codec::Bytes(queued, size);
            return true;
        }
        return seal_tls(queued, size, wire);
    }
    // Bytes the link itself has to send (handshake messages, tickets), made from its session
    // now; empty when there are none. Valid until the next take_output() or seal(): call it
    // only with no send of this connection in flight.
    codec::Bytes take_output() noexcept {
        return bytes_pass_through_ ? codec::Bytes() : take_tls_output();
    }
    // False when take_output() is always empty (the socket carries the Modbus bytes).
    bool may_have_output() const noexcept { return !bytes_pass_through_; }

    // With RTU answers carry no transaction id: after a timeout a late answer would pass for
    // the next request's, so the connection has to go.
    bool matches_answers_by_id() const noexcept { return kind_ != Kind::Rtu; }
    // The error a receive ended with is the kernel's TLS refusing a record the peer sent
    // (close_notify, an alert, a TLS 1.3 KeyUpdate it cannot follow).
    bool is_record_layer_error(int result) const noexcept;

    // The kernel's TLS: whether this link could hand its record layer over now, and doing it
    // (`fd` the socket, `real_fd` false for a direct descriptor).
    bool may_hand_off() const noexcept;
    net::KtlsHandOffResult hand_off(int fd, bool real_fd) noexcept;

    // After SetUp: how long the set-up took and whether it resumed an earlier session.
    std::uint64_t set_up_ns() const noexcept;
    bool resumed() const noexcept;
    // Whether this link ever carried an answer's bytes (over all its connections).
    bool carried_data() const noexcept;
    const std::string& error() const noexcept;

  private:
    struct Tls;  // link_tls.cpp

    bool next_rtu_answer(codec::TcpFrame& frame, LinkInput& end) noexcept;
    // TLS: ciphertext in, plaintext into scratch (`plain`); the set-up first when it is going.
    LinkInput open_tls(codec::Bytes received, std::int64_t now, std::vector<std::uint8_t>& scratch,
                       codec::Bytes& plain);
    bool seal_tls(const std::uint8_t* queued, std::size_t size, codec::Bytes& wire) noexcept;
    codec::Bytes take_tls_output() noexcept;

    Kind kind_;
    // The socket carries the Modbus bytes themselves: MBAP, RTU, and TLS once the kernel has
    // its record layer.
    bool bytes_pass_through_;
    codec::MbapSplitter mbap_;
    std::unique_ptr<codec::RtuSplitter> rtu_;  // Kind::Rtu only
    std::uint16_t rtu_transaction_ = 0;
    // Kind::Tls only, with all a TLS link keeps (its set-up's times, its error): a plain
    // connection stays small, its hot fields within fewer cache lines.
    std::unique_ptr<Tls> tls_;
};

}  // namespace mbstorm::load
