// The first flight of a TLS client, made by OpenSSL without a certificate: the bytes a TLS
// client opens a connection with, for sending where TLS is not spoken. The fields OpenSSL
// fills at random are set to a fixed pattern: the same bytes every time (never completed).
#pragma once

#include <cstdint>
#include <vector>

namespace mbstorm::net {

// A ClientHello record offering TLS 1.2 and 1.3 (or 1.2 alone), the same bytes at every call;
// empty if OpenSSL fails.
std::vector<std::uint8_t> tls_client_hello(bool tls12_only);

}  // namespace mbstorm::net
