// Shared by `fuzz` and `replay`: parse --target and refuse non-loopback targets unless
// --allow-remote is given (fuzzing changes a device's outputs).
#pragma once

#include <memory>
#include <string>

#include "cli/transport_options.hpp"
#include "net/socket.hpp"
#include "netfuzz/link.hpp"

namespace mbstorm::cli {

// False with `error` for an unparsable target or a remote one without permission.
bool resolve_fuzz_target(const std::string& text, bool allow_remote, net::Endpoint& out,
                         std::string& error);

// What `fuzz` and `replay` open links with: the --target (checked as above) reached over the
// chosen transport. Null with `error` when the target or the transport options cannot be used.
std::shared_ptr<netfuzz::Connector> make_fuzz_connector(const std::string& target,
                                                        bool allow_remote,
                                                        const TransportOptions& transport,
                                                        std::string& error);

}  // namespace mbstorm::cli
