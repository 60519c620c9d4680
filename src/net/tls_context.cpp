#include "net/tls_context.hpp"

#include <openssl/asn1.h>
#include <openssl/err.h>
#include <openssl/objects.h>
#include <openssl/ssl.h>
#include <openssl/x509v3.h>

#include "net/kernel_tls.hpp"
#include "net/ktls_offload.hpp"

namespace mbstorm::net {

namespace {

constexpr const char* kRoleOid = "1.3.6.1.4.1.50316.802.1";

// Server side: a client certificate that verified must also carry a role, else the
// specification has the connection refused at the handshake.
int verify_with_role(int preverify_ok, X509_STORE_CTX* store) {
    if (!preverify_ok) return 0;
    if (X509_STORE_CTX_get_error_depth(store) != 0) return 1;
    X509* cert = X509_STORE_CTX_get_current_cert(store);
    if (tls_certificate_role(cert).empty()) {
        X509_STORE_CTX_set_error(store, X509_V_ERR_APPLICATION_VERIFICATION);
        return 0;
    }
    return 1;
}

// A certificate, key or CA file that cannot be used as given.
Error unusable(std::string why) {
    return Error(ErrorCode::InvalidInput, std::move(why));
}

}  // namespace

std::string tls_last_error() {
    unsigned long code = 0, newest = 0;
    while ((code = ERR_get_error()) != 0) newest = code;
    if (newest == 0) return "unknown TLS error";
    char text[256];
    ERR_error_string_n(newest, text, sizeof text);
    return text;
}

std::string tls_certificate_role(X509* cert) {
    if (cert == nullptr) return {};
    ASN1_OBJECT* oid = OBJ_txt2obj(kRoleOid, 1);
    if (oid == nullptr) return {};
    const int at = X509_get_ext_by_OBJ(cert, oid, -1);
    ASN1_OBJECT_free(oid);
    if (at < 0) return {};
    X509_EXTENSION* ext = X509_get_ext(cert, at);
    const ASN1_OCTET_STRING* der = X509_EXTENSION_get_data(ext);
    const unsigned char* const start = ASN1_STRING_get0_data(der);
    const unsigned char* p = start;
    ASN1_UTF8STRING* role = d2i_ASN1_UTF8STRING(nullptr, &p, ASN1_STRING_length(der));
    if (role == nullptr) {
        ERR_clear_error();
        return {};
    }
    // The extension is the UTF8String and nothing else: bytes after it make it no role.
    if (p != start + ASN1_STRING_length(der)) {
        ASN1_UTF8STRING_free(role);
        return {};
    }
    std::string out(reinterpret_cast<const char*>(ASN1_STRING_get0_data(role)),
                    static_cast<std::size_t>(ASN1_STRING_length(role)));
    ASN1_UTF8STRING_free(role);
    return out;
}

Result<std::shared_ptr<TlsContext>> TlsContext::create(TlsSide side, const TlsFiles& files) {
    const bool server = side == TlsSide::Server;
    SSL_CTX* ctx = SSL_CTX_new(server ? TLS_server_method() : TLS_client_method());
    if (ctx == nullptr) return Error(ErrorCode::Unsupported, tls_last_error());
    std::shared_ptr<TlsContext> out(new TlsContext(ctx, side));
    SSL_CTX_set_min_proto_version(ctx, TLS1_2_VERSION);
    SSL_CTX_set_max_proto_version(ctx, TLS1_3_VERSION);
    if (files.cert.empty() || files.key.empty() || files.ca.empty()) {
        return unusable("TLS needs --tls-cert, --tls-key and --tls-ca (mutual authentication)");
    }
    if (SSL_CTX_use_certificate_chain_file(ctx, files.cert.c_str()) != 1) {
        return unusable("cannot use certificate " + files.cert + ": " + tls_last_error());
    }
    if (SSL_CTX_use_PrivateKey_file(ctx, files.key.c_str(), SSL_FILETYPE_PEM) != 1) {
        return unusable("cannot use key " + files.key + " with certificate " + files.cert + ": " +
                        tls_last_error());
    }
    if (SSL_CTX_check_private_key(ctx) != 1) {
        ERR_clear_error();
        return unusable("key " + files.key + " does not match certificate " + files.cert);
    }
    if (SSL_CTX_load_verify_locations(ctx, files.ca.c_str(), nullptr) != 1) {
        return unusable("cannot use CA file " + files.ca + ": " + tls_last_error());
    }
    if (server) {
        SSL_CTX_set_verify(ctx, SSL_VERIFY_PEER | SSL_VERIFY_FAIL_IF_NO_PEER_CERT,
                           verify_with_role);
        // Sessions resume from the server's cache (TLS 1.2) or its tickets (TLS 1.3).
        static const unsigned char kSessionId[] = "mbstorm";
        SSL_CTX_set_session_id_context(ctx, kSessionId, sizeof kSessionId - 1);
        SSL_CTX_set_session_cache_mode(ctx, SSL_SESS_CACHE_SERVER);
    } else {
        SSL_CTX_set_verify(ctx, SSL_VERIFY_PEER, nullptr);
        // The client keeps the sessions itself (TlsSession::saved_session).
        SSL_CTX_set_session_cache_mode(ctx, SSL_SESS_CACHE_CLIENT | SSL_SESS_CACHE_NO_INTERNAL);
    }
    // The traffic secrets for a kernel hand-off come from the keylog callback: set only
    // where the kernel could take them (it costs a line of hex per secret per handshake).
    if (kernel_tls().available) KtlsTracker::prepare_context(ctx);
    return out;
}

TlsContext::~TlsContext() {
    SSL_CTX_free(ctx_);
}

}  // namespace mbstorm::net
