#include "cli/transport_options.hpp"

#include <fmt/format.h>

namespace mbstorm::cli {

TransportKind TransportOptions::kind() const noexcept {
    if (!serial_device.empty()) return TransportKind::Serial;
    if (transport == "rtu-over-tcp") return TransportKind::RtuOverTcp;
    if (transport == "tls") return TransportKind::Tls;
    return TransportKind::Tcp;
}

codec::Framing TransportOptions::framing_kind() const noexcept {
    switch (kind()) {
        case TransportKind::Tcp:
        case TransportKind::Tls:
            return codec::Framing::Mbap;
        case TransportKind::RtuOverTcp:
            return codec::Framing::Rtu;
        case TransportKind::Serial:
            return framing == "ascii" ? codec::Framing::Ascii : codec::Framing::Rtu;
    }
    return codec::Framing::Mbap;
}

std::string_view transport_name(TransportKind kind) noexcept {
    switch (kind) {
        case TransportKind::Tcp:
            return "tcp";
        case TransportKind::RtuOverTcp:
            return "rtu-over-tcp";
        case TransportKind::Tls:
            return "tls";
        case TransportKind::Serial:
            return "serial";
    }
    return "?";
}

net::SerialSettings serial_settings(const TransportOptions& o) noexcept {
    net::SerialSettings s;
    s.baud = o.baud;
    s.parity = o.parity == "none"  ? net::Parity::None
               : o.parity == "odd" ? net::Parity::Odd
                                   : net::Parity::Even;
    s.data_bits = o.data_bits;
    s.stop_bits = o.stop_bits;
    return s;
}

void add_transport_options(CLI::App* cmd, TransportOptions& o, TransportSide side) {
    const bool server = side == TransportSide::Server;
    cmd->add_option("--transport", o.transport,
                    "tcp (Modbus TCP, MBAP), rtu-over-tcp (RTU frames on TCP, as gateways "
                    "speak) or tls (Modbus/TCP Security, port 802)")
        ->check(CLI::IsMember({"tcp", "rtu-over-tcp", "tls"}))
        ->capture_default_str();

    // Serial line.
    cmd->add_option("--serial", o.serial_device,
                    server ? "serve on this tty instead of TCP (RTU or ASCII, see --framing)"
                           : "talk to a device on this tty instead of TCP (RTU or ASCII)");
    cmd->add_option("--baud", o.baud, "serial: bits per second")
        ->check(CLI::Range(50u, 4000000u))
        ->capture_default_str();
    cmd->add_option("--parity", o.parity, "serial: parity")
        ->check(CLI::IsMember({"none", "even", "odd"}))
        ->capture_default_str();
    cmd->add_option("--data-bits", o.data_bits, "serial: data bits (RTU needs 8, ASCII 7 or 8)")
        ->check(CLI::Range(7u, 8u))
        ->capture_default_str();
    cmd->add_option("--stop-bits", o.stop_bits, "serial: stop bits")
        ->check(CLI::Range(1u, 2u))
        ->capture_default_str();
    cmd->add_option("--framing", o.framing, "serial: RTU (binary, CRC-16) or ASCII (hex, LRC)")
        ->check(CLI::IsMember({"rtu", "ascii"}))
        ->capture_default_str();

    // TLS.
    cmd->add_option("--tls-cert", o.tls_cert,
                    server ? "TLS: the server's certificate (PEM)"
                           : "TLS: the client's certificate (PEM), carrying its role");
    cmd->add_option("--tls-key", o.tls_key, "TLS: the private key of --tls-cert (PEM)");
    cmd->add_option("--tls-ca", o.tls_ca,
                    "TLS: CA certificates the peer's certificate must chain to (PEM)");
    if (!server)
        cmd->add_flag("--tls-resume", o.tls_resume,
                      "TLS: resume the session when a connection is reopened");
    if (server)
        cmd->add_option("--tls-role", o.tls_roles,
                        "TLS: ROLE=FC,FC-FC,... lets clients whose certificate names ROLE use "
                        "those function codes (repeatable); once any is given, other requests "
                        "get exception 01 (default: every role may use every function)");
}

Error client_tls(const TransportOptions& o, std::shared_ptr<net::TlsContext>& out) {
    out.reset();
    if (o.kind() != TransportKind::Tls) return {};
    Result<std::shared_ptr<net::TlsContext>> context =
        net::TlsContext::create(net::TlsSide::Client, {o.tls_cert, o.tls_key, o.tls_ca});
    if (!context.ok()) return std::move(context).error();
    out = std::move(context).value();
    return {};
}

namespace {

// check_transport's work: "" or why not.
std::string transport_problem(const TransportOptions& o, std::string_view command) {
    const TransportKind kind = o.kind();
    if (kind == TransportKind::Serial && o.transport != "tcp")
        return "--serial and --transport exclude each other (a serial line is its own transport)";
    if (kind == TransportKind::Tcp) return {};
    // RTU over TCP.
    if (kind == TransportKind::RtuOverTcp &&
        (command == "serve" || command == "run" || command == "read" || command == "write" ||
         command == "fuzz" || command == "replay"))
        return {};
    if (kind == TransportKind::Tls) {
        if (command == "serve" || command == "run" || command == "read" || command == "write" ||
            command == "fuzz" || command == "replay")
            return {};
    }
    // Serial: RTU needs eight data bits (the specification's and the CRC's).
    if (kind == TransportKind::Serial && o.framing == "rtu" && o.data_bits != 8)
        return "--framing rtu needs --data-bits 8 (7 data bits suit only ASCII)";
    if (kind == TransportKind::Serial &&
        (command == "serve" || command == "run" || command == "read" || command == "write" ||
         command == "fuzz" || command == "replay"))
        return {};
    // Each transport lifts this as it reaches the subcommand.
    return fmt::format("--{} is not supported by {} yet",
                       kind == TransportKind::Serial
                           ? std::string("serial")
                           : fmt::format("transport {}", transport_name(kind)),
                       command);
}

}  // namespace

Error check_transport(const TransportOptions& o, std::string_view command) {
    std::string why = transport_problem(o, command);
    if (why.empty()) return {};
    return Error(ErrorCode::InvalidInput, std::move(why));
}

}  // namespace mbstorm::cli
