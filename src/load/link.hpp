// How a load connection's received bytes become answers and its requests become bytes to send,
// chosen once per run: plain MBAP, RTU over TCP, or Modbus/TCP Security (TLS over memory BIOs
// in userspace, handed to the kernel's TLS once it can take the records). The worker moves
// bytes between the socket and its link and reacts to what the link says; it never asks which
// link it has (wrk's `struct sock`). A plain MBAP link pays one predictable branch per receive
// and per send, not a call per frame: its splitter loop is inlined into the worker's.
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

// What a link made of received bytes, besides the answers it handed on.
enum class LinkInput : std::uint8_t {
    Answers,      // every whole answer handed on; a partial one waits for more bytes
    SettingUp,    // the link's own set-up (a TLS handshake) took the bytes; its reply waits
    SetUp,        // the set-up finished with these bytes (answers after it handed on)
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

    // Received bytes. Every whole answer goes to on_answer(frame); MBAP frames with a wrong
    // protocol id are counted in bad_protocol and skipped. `scratch` holds decrypted bytes
    // (a TLS link's; shared by the worker's links). On FramingLost, `unframed` is what could
    // not be framed (empty when the link keeps no such bytes).
    // Forced inline, with the splitter loops: the frame loop runs inside the worker's receive
    // handler with its locals in registers, as it did before the link (a call here, and the
    // handler's state reached through a closure, cost about 2 % at 16 x 16).
    template <class OnAnswer>
    [[gnu::always_inline]] inline LinkInput input(codec::Bytes received, std::int64_t now,
                                                  std::vector<std::uint8_t>& scratch,
                                                  std::uint64_t& bad_protocol,
                                                  codec::Bytes& unframed, OnAnswer&& on_answer);

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

    template <class OnAnswer>
    [[gnu::always_inline]] inline LinkInput split_mbap(codec::Bytes bytes,
                                                       std::uint64_t& bad_protocol,
                                                       codec::Bytes& unframed, OnAnswer& on_answer);
    template <class OnAnswer>
    [[gnu::always_inline]] inline LinkInput split_rtu(codec::Bytes bytes, OnAnswer& on_answer);
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

template <class OnAnswer>
LinkInput Link::input(codec::Bytes received, std::int64_t now, std::vector<std::uint8_t>& scratch,
                      std::uint64_t& bad_protocol, codec::Bytes& unframed, OnAnswer&& on_answer) {
    switch (kind_) {
        case Kind::Mbap:
            return split_mbap(received, bad_protocol, unframed, on_answer);
        case Kind::Rtu:
            return split_rtu(received, on_answer);
        case Kind::Tls:
            break;
    }
    codec::Bytes plain;
    const LinkInput opened = open_tls(received, now, scratch, plain);
    if (opened != LinkInput::Answers && opened != LinkInput::SetUp) return opened;
    const LinkInput split = split_mbap(plain, bad_protocol, unframed, on_answer);
    return split == LinkInput::Answers ? opened : split;
}

template <class OnAnswer>
LinkInput Link::split_mbap(codec::Bytes bytes, std::uint64_t& bad_protocol, codec::Bytes& unframed,
                           OnAnswer& on_answer) {
    mbap_.feed(bytes);
    codec::TcpFrame frame;
    for (;;) {
        switch (mbap_.next(frame)) {
            case codec::MbapSplitter::Status::Frame:
                on_answer(frame);
                break;
            case codec::MbapSplitter::Status::BadProtocolId:
                ++bad_protocol;
                break;
            case codec::MbapSplitter::Status::NeedMore:
                return LinkInput::Answers;
            case codec::MbapSplitter::Status::Fatal:
                unframed = bytes;
                return LinkInput::FramingLost;
        }
    }
}

template <class OnAnswer>
LinkInput Link::split_rtu(codec::Bytes bytes, OnAnswer& on_answer) {
    rtu_->feed(bytes);
    codec::TcpFrame frame;
    for (;;) {
        switch (rtu_->next(frame)) {
            case codec::RtuSplitter::Status::Frame:
                frame.header.transaction_id = rtu_transaction_;
                on_answer(frame);
                break;
            case codec::RtuSplitter::Status::NeedMore:
                return LinkInput::Answers;
            case codec::RtuSplitter::Status::Skipped:  // not asked for here: an answer with a
                return LinkInput::BadCrc;              // bad CRC is an error of the target's
            case codec::RtuSplitter::Status::Fatal:
                return rtu_->error() == codec::CodecError::BadCrc ? LinkInput::BadCrc
                                                                  : LinkInput::FramingLost;
        }
    }
}

}  // namespace mbstorm::load
