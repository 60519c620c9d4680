// The transport flags shared by every subcommand that talks to or serves a Modbus device:
// --transport tcp|rtu-over-tcp|tls, the TLS certificate options, and --serial with its line
// settings. One definition, so that run, serve, fuzz, replay, read and write spell them alike.
#pragma once

#include <CLI/CLI.hpp>

#include <memory>

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "codec/framing.hpp"
#include "net/serial_port.hpp"
#include "net/tls_context.hpp"
#include "util/error.hpp"

namespace mbstorm::cli {

enum class TransportKind : std::uint8_t {
    Tcp,         // MBAP over TCP (port 502)
    RtuOverTcp,  // RTU frames (unit, PDU, CRC) on a TCP stream, no MBAP: gateways
    Tls,         // Modbus/TCP Security: MBAP inside TLS with mutual authentication (port 802)
    Serial,      // RTU or ASCII on a tty (--serial)
};

// Which end of the transport the subcommand is: the certificate options and the defaults
// differ (a client sends its role, a server checks it).
enum class TransportSide : std::uint8_t { Client, Server };

struct TransportOptions {
    std::string transport = "tcp";  // tcp | rtu-over-tcp | tls

    // Serial line (--serial DEVICE switches to it).
    std::string serial_device;
    std::uint32_t baud = 19200;
    std::string parity = "even";  // none | even | odd
    unsigned data_bits = 8;
    unsigned stop_bits = 1;
    std::string framing = "rtu";  // rtu | ascii

    // TLS (Modbus/TCP Security).
    std::string tls_cert;                // own certificate (PEM)
    std::string tls_key;                 // its private key (PEM)
    std::string tls_ca;                  // CA certificates that sign the peer's certificate (PEM)
    bool tls_resume = false;             // client: resume sessions on reconnect
    std::vector<std::string> tls_roles;  // server: ROLE=FC,FC-FC,... allow-list rules

    TransportKind kind() const noexcept;
    codec::Framing framing_kind() const noexcept;
};

// Registers the flags on `cmd` into `o`.
void add_transport_options(CLI::App* cmd, TransportOptions& o, TransportSide side);

// None when `command` can use the chosen transport, else why not (InvalidInput).
Error check_transport(const TransportOptions& o, std::string_view command);

std::string_view transport_name(TransportKind kind) noexcept;

// --transport tls on a client: the TLS context from the certificate options into `out` (left
// empty for other transports), or why the files cannot be used.
Error client_tls(const TransportOptions& o, std::shared_ptr<net::TlsContext>& out);
// The --serial line settings as the serial port takes them.
net::SerialSettings serial_settings(const TransportOptions& o) noexcept;

}  // namespace mbstorm::cli
