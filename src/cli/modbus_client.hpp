// A blocking Modbus TCP client for one transaction at a time (`mbstorm read` / `write`):
// the load engine pipelines thousands; this only needs to be simple and to time out.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "codec/bytes.hpp"
#include "codec/framing.hpp"
#include "codec/mbap.hpp"
#include "codec/pdu.hpp"
#include "net/socket.hpp"
#include "net/tls_session.hpp"

namespace mbstorm::cli {

class ModbusClient {
  public:
    // Mbap (Modbus TCP) or Rtu (RTU over TCP: no transaction id, the next frame is the answer).
    explicit ModbusClient(codec::Framing framing = codec::Framing::Mbap) : framing_(framing) {}

    // Connects within `timeout_ms` (with `tls`, the handshake too); "" on success, else the
    // system's or TLS's reason.
    std::string connect(const net::Endpoint& target, int timeout_ms,
                        std::shared_ptr<net::TlsContext> tls = nullptr);

    // Sends `request` (a PDU) to `unit` and waits up to `timeout_ms` for the answer with the
    // same transaction id, decoded into `response` (which views `buffer_`, valid until the
    // next call). "" on success, else what went wrong (timeout, close, malformed answer).
    std::string transact(std::uint8_t unit, codec::Bytes request, int timeout_ms,
                         codec::Response& response);

  private:
    std::string transact_rtu(std::uint8_t unit, codec::Bytes request, int timeout_ms,
                             codec::Response& response);
    // The answer `frame` carries for `unit`, decoded into `response`: "" or why it is not one.
    std::string take_answer(const codec::TcpFrame& frame, std::uint8_t unit,
                            codec::Response& response);
    codec::Framing framing_;
    using Deadline = std::chrono::steady_clock::time_point;
    // The bytes to the socket (through the TLS session when there is one); "" or why not.
    std::string send_all(const std::uint8_t* data, std::size_t size, Deadline deadline);
    std::string send_tls_output(Deadline deadline);
    // Waits for bytes from the socket; plaintext into `out`/`size` (0 with TLS: only a
    // handshake or ticket record came). "" or why not.
    std::string receive(std::uint8_t* out, std::size_t capacity, std::size_t& size,
                        Deadline deadline, int timeout_ms);

    std::optional<net::TlsSession> tls_;
    net::UniqueFd fd_;
    std::uint16_t next_tid_ = 1;
    std::vector<std::uint8_t> buffer_;
};

}  // namespace mbstorm::cli
