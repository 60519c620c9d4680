// What a target that does not speak Modbus/TCP answered instead: the first bytes of a
// receive the engine could not frame, named when they look like a protocol people point a
// Modbus client at by mistake (an HTTP server, TLS, SSH), else shown as text or hex.
#pragma once

#include <string>

#include "codec/bytes.hpp"

namespace mbstorm::load {

// "an HTTP server (HTTP/1.0 400 Bad)", "TLS: try --transport tls (16 03 03 00 4A)", ...;
// empty for an empty sample.
std::string describe_foreign_bytes(codec::Bytes sample);

}  // namespace mbstorm::load
