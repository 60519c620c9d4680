#include "cli/fuzz_target.hpp"

#include <arpa/inet.h>

#include <cstring>

#include "load/preflight.hpp"
#include "load/write_safety.hpp"
#include "netfuzz/serial_link.hpp"
#include "netfuzz/tls_link.hpp"

namespace mbstorm::cli {

Result<net::Endpoint> resolve_fuzz_target(const std::string& text, bool allow_remote,
                                          std::uint16_t default_port) {
    Result<net::Endpoint> endpoint = net::parse_endpoint(text, default_port);
    if (!endpoint.ok()) return std::move(endpoint).error();
    const net::Endpoint out = *endpoint;
    // The rule run and write apply to writes: 127.0.0.0/8, ::1 and ::ffff:127.0.0.0/104.
    const bool loopback = load::is_loopback_address(load::numeric_address(out));
    if (!loopback && !allow_remote) {
        return Error(ErrorCode::Refused,
                     "target " + out.to_string() +
                         " is not a loopback address; fuzzing writes to the device and may "
                         "change its outputs: pass --allow-remote if you mean it");
    }
    return out;
}

Result<std::shared_ptr<netfuzz::Connector>> make_fuzz_connector(const std::string& target,
                                                                bool allow_remote,
                                                                const TransportOptions& transport) {
    using Made = Result<std::shared_ptr<netfuzz::Connector>>;
    // Each transport adds its own case here as it reaches fuzz and replay.
    switch (transport.kind()) {
        case TransportKind::Tcp: {
            Result<net::Endpoint> endpoint = resolve_fuzz_target(target, allow_remote);
            if (!endpoint.ok()) return std::move(endpoint).error();
            return Made(std::make_shared<netfuzz::TcpConnector>(*endpoint));
        }
        case TransportKind::Tls: {
            Result<net::Endpoint> endpoint = resolve_fuzz_target(target, allow_remote, 802);
            if (!endpoint.ok()) return std::move(endpoint).error();
            std::shared_ptr<net::TlsContext> ctx;
            if (Error error = client_tls(transport, ctx); !error.ok()) return error;
            return Made(std::make_shared<netfuzz::TlsConnector>(*endpoint, std::move(ctx),
                                                                transport.tls_resume));
        }
        case TransportKind::RtuOverTcp: {
            Result<net::Endpoint> endpoint = resolve_fuzz_target(target, allow_remote);
            if (!endpoint.ok()) return std::move(endpoint).error();
            return Made(std::make_shared<netfuzz::TcpConnector>(*endpoint, codec::Framing::Rtu));
        }
        case TransportKind::Serial:
            // A tty is local by nature; --target is not used.
            return Made(std::make_shared<netfuzz::SerialConnector>(
                transport.serial_device, serial_settings(transport), transport.framing_kind()));
    }
    return Error(ErrorCode::Unsupported, "this transport cannot be fuzzed yet");
}

std::string connector_failure(const netfuzz::Connector& connector) {
    if (const auto* tls = dynamic_cast<const netfuzz::TlsConnector*>(&connector)) {
        if (std::string why = tls->last_failure(); !why.empty()) return " (" + why + ")";
    }
    return {};
}

}  // namespace mbstorm::cli
