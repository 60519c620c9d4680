// Shared by `fuzz` and `replay`: parse --target and refuse non-loopback targets unless
// --allow-remote is given (fuzzing changes a device's outputs).
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "cli/transport_options.hpp"
#include "net/socket.hpp"
#include "netfuzz/link.hpp"
#include "util/error.hpp"

namespace mbstorm::cli {

// InvalidInput for an unparsable target, Refused for a remote one without permission.
Result<net::Endpoint> resolve_fuzz_target(const std::string& text, bool allow_remote,
                                          std::uint16_t default_port = 502);

// What `fuzz` and `replay` open links with: the --target (checked as above) reached over the
// chosen transport; an Error when the target or the transport options cannot be used.
Result<std::shared_ptr<netfuzz::Connector>> make_fuzz_connector(const std::string& target,
                                                                bool allow_remote,
                                                                const TransportOptions& transport);

// Why the connector's last link could not be opened or broke, beyond an errno (a TLS
// handshake's refusal, an alert), as " (...)"; empty when it has nothing to add.
std::string connector_failure(const netfuzz::Connector& connector);

}  // namespace mbstorm::cli
