// How a served connection's received bytes become requests and its answers become bytes to
// send, chosen once per server: plain MBAP, RTU over TCP, or Modbus/TCP Security (TLS over
// memory BIOs, handed to the kernel's TLS once it can take the records). The worker gives its
// link what a recv brought and what its output queue holds, and reacts to what the link says;
// it never asks which link it has (wrk's `struct sock`). A plain MBAP link costs a predictable
// branch per receive and per send; its frame loop is inlined into the worker's.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "codec/bytes.hpp"
#include "codec/exception_code.hpp"
#include "codec/limits.hpp"
#include "codec/mbap.hpp"
#include "codec/rtu_stream.hpp"
#include "net/ktls_offload.hpp"
#include "net/tls_session.hpp"
#include "server/tls_roles.hpp"

namespace mbstorm::server {

// What a link made of received bytes, besides the requests read from it.
enum class LinkInput : std::uint8_t {
    Drained,      // requests to read (or all read); a partial one waits for more bytes
    Stopped,      // the worker closed the connection while serving a request
    SettingUp,    // the link's own set-up (a TLS handshake) took the bytes; its reply waits
    SetUpFailed,  // the set-up was refused or malformed: its alert may wait in output
    PeerClosed,   // the peer ended its input (close_notify): what came before is answered
    PeerFailed,   // a record that does not verify: the connection goes
    FramingLost,  // no frame boundary can be found again
    BadCrc,       // an RTU frame's CRC failed and no length rule finds the next frame
};

class Link {
  public:
    enum class Kind : std::uint8_t { Mbap, Rtu, Tls };

    Link();
    Link(Link&&) noexcept;
    Link& operator=(Link&&) noexcept;
    ~Link();

    // A new connection on this slot. tls: the server context (Kind::Tls); roles: which
    // functions each client role may use; offload: track the session for the kernel's TLS.
    // False when its TLS session could not be made.
    bool accepted(Kind kind, const std::shared_ptr<net::TlsContext>& tls, const TlsRoles* roles,
                  bool offload);
    // The slot is free again (a TLS session goes; an RTU splitter stays for the next one).
    void released() noexcept;

    // Received bytes, taken in: Drained when requests may follow from next_request(),
    // SettingUp / SetUpFailed when a set-up took them. `set_up`: a set-up finished with them
    // (before the requests after it). `scratch` holds a TLS link's plaintext (shared by the
    // worker's links), read by next_request() until it returns false.
    LinkInput take(codec::Bytes received, std::vector<std::uint8_t>& scratch, bool& set_up) {
        if (kind_ == Kind::Rtu) {
            rtu_->feed(received);
            return LinkInput::Drained;
        }
        if (bytes_pass_through_) [[likely]] {  // MBAP, or TLS once the kernel has the records
            mbap_.feed(received);
            return LinkInput::Drained;
        }
        return take_tls(received, scratch, set_up);
    }
    // The next whole request of the bytes taken: true with `frame` set. False when none is
    // left, `end` saying why: Drained (a partial one waits for more bytes), FramingLost,
    // BadCrc, PeerClosed, PeerFailed. `discarded` counts MBAP frames with a wrong protocol id,
    // `crc_skipped` RTU frames dropped for their CRC. Nothing of the link may be touched after
    // the worker closed the connection (its slot may be free).
    // Inline, pulled by the worker's own loop: the request's handling stays in the receive
    // handler with its locals in registers (a sink called per frame through references cost
    // about 6 instructions a request); RTU and TLS plaintext are asked for only once the MBAP
    // splitter is drained.
    [[gnu::always_inline]] bool next_request(codec::TcpFrame& frame, LinkInput& end,
                                             std::uint64_t& discarded,
                                             std::uint64_t& crc_skipped) noexcept {
        if (mbap_.next_modbus(frame, discarded)) return true;
        if (mbap_.failed()) {
            end = LinkInput::FramingLost;
            return false;
        }
        if (kind_ == Kind::Mbap) [[likely]] {
            end = LinkInput::Drained;
            return false;
        }
        return next_request_rest(frame, end, discarded, crc_skipped);
    }
    // Bytes of a request still arriving that the link holds, or a TLS record's that has not
    // all come (nonzero: the frame clock runs on them).
    std::size_t buffered() const noexcept {
        switch (kind_) {
            case Kind::Mbap:
                return mbap_.buffered();
            case Kind::Rtu:
                return rtu_->buffered();
            case Kind::Tls:
                return mbap_.buffered() + (record_partly_in() ? 1 : 0);
        }
        return 0;
    }
    // Part of a TLS record has come and the rest has not: a frame still arriving, timed too.
    bool record_partly_in() const noexcept;
    // Setting up (a TLS handshake not finished yet).
    bool setting_up() const noexcept;

    // Answers: the PDU goes `answer_offset()` bytes into the reserved space; frame_answer
    // writes the framing around `pdu_size` bytes of it and returns the answer's size.
    std::size_t answer_offset() const noexcept {
        return kind_ == Kind::Rtu ? 1 : codec::limits::kMbapHeader;  // RTU: the address
    }
    std::size_t frame_answer(std::uint8_t* p, const codec::TcpFrame& request,
                             std::size_t pdu_size) const noexcept;
    static constexpr std::size_t kMaxExceptionSize =
        codec::kExceptionAduSize > codec::kRtuExceptionAduSize ? codec::kExceptionAduSize
                                                               : codec::kRtuExceptionAduSize;
    // An exception answer to `request` at p (kMaxExceptionSize bytes reserved); its size.
    std::size_t write_exception(std::uint8_t* p, const codec::TcpFrame& request,
                                codec::ExceptionCode code) const noexcept;
    // Which functions the peer may use (a TLS client's role); nullptr: every one.
    const FunctionSet* allowed() const noexcept { return allowed_; }

    // What to send: the output queue's bytes themselves (`queued`, `size`), or the link's own
    // (ciphertext of them, a handshake's messages). Empty when there is nothing; false when the
    // link failed. Call only with no send in flight.
    bool outgoing(const std::uint8_t* queued, std::size_t size, codec::Bytes& wire) {
        if (!bytes_pass_through_) return outgoing_tls(queued, size, wire);
        wire = codec::Bytes(queued, size);
        return true;
    }
    // `n` bytes of the last outgoing() went: how many of the output queue's bytes are done.
    std::size_t sent(std::size_t n) noexcept { return bytes_pass_through_ ? n : sent_tls(n); }
    // The link has bytes of its own to send (a handshake's flight, tickets, an alert).
    bool has_own_output() const noexcept;
    // False when the link never has bytes of its own, holds no partial record and has no
    // record layer to hand to the kernel: the socket carries the Modbus bytes themselves.
    bool may_need_care() const noexcept { return !bytes_pass_through_; }

    // The error a receive ended with is the kernel's TLS refusing a record the peer sent.
    bool is_record_layer_error(int result) const noexcept;
    // The kernel's TLS: whether the link could hand its record layer over now (none of its
    // bytes in flight or held), and doing it.
    bool may_hand_off() const noexcept;
    net::KtlsHandOffResult hand_off(int fd, bool real_fd) noexcept;
    bool resumed() const noexcept;

  private:
    struct Tls;

    LinkInput take_tls(codec::Bytes received, std::vector<std::uint8_t>& scratch, bool& set_up);
    // After the MBAP splitter is drained: an RTU link's next frame, or a TLS link's next
    // plaintext split (next_request's contract).
    bool next_request_rest(codec::TcpFrame& frame, LinkInput& end, std::uint64_t& discarded,
                           std::uint64_t& crc_skipped) noexcept;
    // The handshake's step on new ciphertext: SetUp when it finished now (roles looked up).
    enum class Handshake : std::uint8_t { Done, SetUp, Going, Failed };
    Handshake step_handshake(codec::Bytes received);
    bool outgoing_tls(const std::uint8_t* queued, std::size_t size, codec::Bytes& wire);
    std::size_t sent_tls(std::size_t n) noexcept;
    // The next plaintext into scratch: its size, 0 with `end` set when the input ended.
    std::size_t read_plain(std::vector<std::uint8_t>& scratch, LinkInput& end);

    Kind kind_ = Kind::Mbap;
    bool bytes_pass_through_ = true;  // the socket carries the Modbus bytes themselves
    codec::MbapSplitter mbap_;
    std::unique_ptr<codec::RtuSplitter> rtu_;  // made when an RTU link first uses the slot
    std::unique_ptr<Tls> tls_;                 // Kind::Tls, per connection
    const FunctionSet* allowed_ = nullptr;
};

}  // namespace mbstorm::server
