// OpenSSL contexts for Modbus/TCP Security: TLS 1.2 and 1.3, mutual X.509 authentication
// against a CA file, and the client's role read from its certificate (extension OID
// 1.3.6.1.4.1.50316.802.1). Knows nothing of Modbus beyond that OID.
#pragma once

#include <memory>
#include <string>

#include "util/error.hpp"

using SSL_CTX = struct ssl_ctx_st;
using SSL = struct ssl_st;
using X509 = struct x509_st;

namespace mbstorm::net {

enum class TlsSide : unsigned char { Client, Server };

struct TlsFiles {
    std::string cert;  // own certificate chain (PEM)
    std::string key;   // its private key (PEM)
    std::string ca;    // CA certificates the peer's must chain to (PEM)
};

class TlsContext {
  public:
    // Loads the files and sets verification: a server refuses a client without a certificate
    // that chains to `ca` and carries a role; a client verifies the server against `ca`.
    // InvalidInput saying which when a file is missing or cannot be used.
    static Result<std::shared_ptr<TlsContext>> create(TlsSide side, const TlsFiles& files);
    ~TlsContext();
    TlsContext(const TlsContext&) = delete;
    TlsContext& operator=(const TlsContext&) = delete;

    SSL_CTX* get() const noexcept { return ctx_; }
    TlsSide side() const noexcept { return side_; }

  private:
    TlsContext(SSL_CTX* ctx, TlsSide side) : ctx_(ctx), side_(side) {}
    SSL_CTX* ctx_;
    TlsSide side_;
};

// The role the Modbus/TCP Security extension names in `cert` (an ASN.1 UTF8String); empty
// when the certificate has no such extension or it does not decode.
std::string tls_certificate_role(X509* cert);

// The newest OpenSSL error on this thread's queue as text (and the queue emptied).
std::string tls_last_error();

}  // namespace mbstorm::net
