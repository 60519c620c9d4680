// A blocking Modbus TCP client for one transaction at a time (`mbstorm read` / `write`):
// the load engine pipelines thousands; this only needs to be simple and to time out.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "codec/bytes.hpp"
#include "codec/framing.hpp"
#include "codec/pdu.hpp"
#include "net/socket.hpp"

namespace mbstorm::cli {

class ModbusClient {
  public:
    // Mbap (Modbus TCP) or Rtu (RTU over TCP: no transaction id, the next frame is the answer).
    explicit ModbusClient(codec::Framing framing = codec::Framing::Mbap) : framing_(framing) {}

    // Connects within `timeout_ms`; "" on success, else the system's reason.
    std::string connect(const net::Endpoint& target, int timeout_ms);

    // Sends `request` (a PDU) to `unit` and waits up to `timeout_ms` for the answer with the
    // same transaction id, decoded into `response` (which views `buffer_`, valid until the
    // next call). "" on success, else what went wrong (timeout, close, malformed answer).
    std::string transact(std::uint8_t unit, codec::Bytes request, int timeout_ms,
                         codec::Response& response);

  private:
    std::string transact_rtu(std::uint8_t unit, codec::Bytes request, int timeout_ms,
                             codec::Response& response);
    codec::Framing framing_;
    net::UniqueFd fd_;
    std::uint16_t next_tid_ = 1;
    std::vector<std::uint8_t> buffer_;
};

}  // namespace mbstorm::cli
