#include "net/tls_hello.hpp"

#include <openssl/bio.h>
#include <openssl/err.h>
#include <openssl/ssl.h>

#include <algorithm>
#include <cstddef>

namespace mbstorm::net {
namespace {

using Bytes = std::vector<std::uint8_t>;

// A big-endian 16-bit field at `at`, or 0 past the end.
std::size_t field16(const Bytes& b, std::size_t at) {
    return at + 2 <= b.size() ? static_cast<std::size_t>(b[at] << 8 | b[at + 1]) : 0;
}

// Sets `n` bytes at `at` (clipped to the record) to a fixed pattern.
void fix(Bytes& b, std::size_t at, std::size_t n) {
    for (std::size_t i = 0; i < n && at + i < b.size(); ++i)
        b[at + i] = static_cast<std::uint8_t>(0xA0 + (i & 0x1F));
}

// The key shares of a key_share extension whose data starts at `at`.
void fix_key_shares(Bytes& b, std::size_t at, std::size_t end) {
    std::size_t p = at + 2;  // client_shares length
    while (p + 4 <= end) {
        const std::size_t key = field16(b, p + 2);
        fix(b, p + 4, std::min(key, end - (p + 4)));
        p += 4 + key;
    }
}

// The fields OpenSSL fills at random (client random, legacy session id, key shares) set to a
// fixed pattern: the same bytes every time, so that a fuzz run repeats with its seed.
void fix_random_fields(Bytes& b) {
    constexpr std::size_t kRandom = 5 + 4 + 2;  // record header, handshake header, version
    fix(b, kRandom, 32);
    std::size_t p = kRandom + 32;
    if (p >= b.size()) return;
    const std::size_t session_id = b[p];
    fix(b, p + 1, session_id);
    p += 1 + session_id;
    p += 2 + field16(b, p);               // cipher suites
    p += 1 + (p < b.size() ? b[p] : 0u);  // compression methods
    const std::size_t end = std::min(b.size(), p + 2 + field16(b, p));
    for (p += 2; p + 4 <= end;) {
        const std::size_t type = field16(b, p), size = field16(b, p + 2);
        if (type == 0x0033) fix_key_shares(b, p + 4, std::min(end, p + 4 + size));
        p += 4 + size;
    }
}

}  // namespace

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
    fix_random_fields(out);
    return out;
}

}  // namespace mbstorm::net
