// Shared by `fuzz` and `replay`: parse --target and refuse non-loopback targets unless
// --allow-remote is given (fuzzing changes a device's outputs).
#pragma once

#include <string>

#include "net/socket.hpp"

namespace mbstorm::cli {

// False with `error` for an unparsable target or a remote one without permission.
bool resolve_fuzz_target(const std::string& text, bool allow_remote, net::Endpoint& out,
                         std::string& error);

}  // namespace mbstorm::cli
