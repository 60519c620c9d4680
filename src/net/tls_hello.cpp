#include "net/tls_hello.hpp"

#include <openssl/bio.h>
#include <openssl/err.h>
#include <openssl/ssl.h>

namespace mbstorm::net {

std::vector<std::uint8_t> tls_client_hello(bool tls12_only) {
    std::vector<std::uint8_t> out;
    SSL_CTX* ctx = SSL_CTX_new(TLS_client_method());
    if (ctx == nullptr) return out;
    SSL_CTX_set_min_proto_version(ctx, TLS1_2_VERSION);
    SSL_CTX_set_max_proto_version(ctx, tls12_only ? TLS1_2_VERSION : TLS1_3_VERSION);
    SSL* ssl = SSL_new(ctx);
    BIO* in = BIO_new(BIO_s_mem());
    BIO* to_peer = BIO_new(BIO_s_mem());
    if (ssl != nullptr && in != nullptr && to_peer != nullptr) {
        BIO_set_mem_eof_return(in, -1);  // no answer yet, not the end
        SSL_set_bio(ssl, in, to_peer);
        in = to_peer = nullptr;  // owned by ssl now
        SSL_set_connect_state(ssl);
        SSL_do_handshake(ssl);  // writes the ClientHello, then wants the server's answer
        BIO* wbio = SSL_get_wbio(ssl);
        const auto pending = static_cast<int>(BIO_ctrl_pending(wbio));
        out.resize(static_cast<std::size_t>(pending));
        const int n = pending > 0 ? BIO_read(wbio, out.data(), pending) : 0;
        out.resize(static_cast<std::size_t>(n > 0 ? n : 0));
    }
    BIO_free(in);
    BIO_free(to_peer);
    SSL_free(ssl);
    SSL_CTX_free(ctx);
    ERR_clear_error();
    return out;
}

}  // namespace mbstorm::net
