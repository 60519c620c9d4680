#include "net/tls_session.hpp"

#include <openssl/bio.h>
#include <openssl/err.h>
#include <openssl/ssl.h>
#include <openssl/x509.h>

namespace mbstorm::net {

TlsSession::TlsSession(std::shared_ptr<TlsContext> ctx, SSL_SESSION* resume)
    : ctx_(std::move(ctx)) {
    ssl_ = SSL_new(ctx_->get());
    if (ssl_ == nullptr) {
        error_ = tls_last_error();
        return;
    }
    in_ = BIO_new(BIO_s_mem());
    out_ = BIO_new(BIO_s_mem());
    if (in_ == nullptr || out_ == nullptr) {
        BIO_free(in_);
        BIO_free(out_);
        SSL_free(ssl_);
        ssl_ = nullptr;
        error_ = "out of memory for TLS buffers";
        return;
    }
    // An empty memory BIO means "retry later", not end of file.
    BIO_set_mem_eof_return(in_, -1);
    BIO_set_mem_eof_return(out_, -1);
    SSL_set_bio(ssl_, in_, out_);
    if (ctx_->side() == TlsSide::Server) {
        SSL_set_accept_state(ssl_);
    } else {
        SSL_set_connect_state(ssl_);
        if (resume != nullptr) SSL_set_session(ssl_, resume);
    }
}

TlsSession::~TlsSession() {
    if (ssl_ == nullptr) return;
    // Freed without a shutdown, OpenSSL takes the session for a broken one and never
    // resumes it; a connection that simply ends (the peer closed, or we did) is no such thing.
    if (established_) {
        SSL_set_quiet_shutdown(ssl_, 1);
        SSL_shutdown(ssl_);
        ERR_clear_error();
    }
    SSL_free(ssl_);
}

void TlsSession::feed(const std::uint8_t* data, std::size_t size) noexcept {
    if (ssl_ != nullptr && size > 0) BIO_write(in_, data, static_cast<int>(size));
}

TlsStatus TlsSession::fail(int rc) noexcept {
    switch (SSL_get_error(ssl_, rc)) {
        case SSL_ERROR_WANT_READ:
        case SSL_ERROR_WANT_WRITE:
            return TlsStatus::WantMore;
        case SSL_ERROR_ZERO_RETURN:
            return TlsStatus::Closed;
        default:
            break;
    }
    if (error_.empty()) {
        const long verify = SSL_get_verify_result(ssl_);
        error_ = verify != X509_V_OK && !established_
                     ? std::string("certificate: ") + X509_verify_cert_error_string(verify)
                     : tls_last_error();
    }
    ERR_clear_error();
    return TlsStatus::Failed;
}

TlsStatus TlsSession::handshake() noexcept {
    if (ssl_ == nullptr) return TlsStatus::Failed;
    if (established_) return TlsStatus::Ok;
    const int rc = SSL_do_handshake(ssl_);
    if (rc == 1) {
        established_ = true;
        return TlsStatus::Ok;
    }
    return fail(rc);
}

TlsStatus TlsSession::read(std::uint8_t* out, std::size_t capacity, std::size_t& size) noexcept {
    size = 0;
    if (ssl_ == nullptr) return TlsStatus::Failed;
    if (!established_) {
        const TlsStatus hs = handshake();
        if (hs != TlsStatus::Ok) return hs;
    }
    const int rc = SSL_read(ssl_, out, static_cast<int>(capacity));
    if (rc > 0) {
        size = static_cast<std::size_t>(rc);
        return TlsStatus::Ok;
    }
    return fail(rc);
}

TlsStatus TlsSession::write(const std::uint8_t* data, std::size_t size) noexcept {
    if (ssl_ == nullptr || !established_) return TlsStatus::Failed;
    if (size == 0) return TlsStatus::Ok;
    const int rc = SSL_write(ssl_, data, static_cast<int>(size));
    if (rc == static_cast<int>(size)) return TlsStatus::Ok;
    return fail(rc) == TlsStatus::WantMore ? TlsStatus::WantMore : TlsStatus::Failed;
}

std::size_t TlsSession::pending_output() const noexcept {
    return ssl_ == nullptr ? 0 : BIO_ctrl_pending(out_);
}

bool TlsSession::partial_input() const noexcept {
    return ssl_ != nullptr && (BIO_ctrl_pending(in_) > 0 || SSL_has_pending(ssl_) == 1);
}

std::size_t TlsSession::take_output(std::vector<std::uint8_t>& out) {
    const std::size_t pending = pending_output();
    if (pending == 0) return 0;
    const std::size_t at = out.size();
    out.resize(at + pending);
    const int n = BIO_read(out_, out.data() + at, static_cast<int>(pending));
    out.resize(at + static_cast<std::size_t>(n > 0 ? n : 0));
    return out.size() - at;
}

void TlsSession::close() noexcept {
    if (ssl_ != nullptr && established_) {
        SSL_shutdown(ssl_);
        ERR_clear_error();
    }
}

std::string TlsSession::peer_role() const {
    if (ssl_ == nullptr) return {};
    X509* cert = SSL_get1_peer_certificate(ssl_);
    std::string role = tls_certificate_role(cert);
    X509_free(cert);
    return role;
}

bool TlsSession::resumed() const noexcept {
    return ssl_ != nullptr && SSL_session_reused(ssl_);
}

const char* TlsSession::version() const noexcept {
    return ssl_ == nullptr ? "" : SSL_get_version(ssl_);
}

SSL_SESSION* TlsSession::saved_session() const noexcept {
    if (ssl_ == nullptr) return nullptr;
    SSL_SESSION* s = SSL_get1_session(ssl_);
    if (s != nullptr && !SSL_SESSION_is_resumable(s)) {
        SSL_SESSION_free(s);
        return nullptr;
    }
    return s;
}

void TlsSession::track_for_offload() {
    if (ssl_ == nullptr || ktls_) return;
    ktls_ = std::make_unique<KtlsTracker>();
    ktls_->attach(ssl_);
}

KtlsReadiness TlsSession::offload_readiness() const noexcept {
    KtlsReadiness r;
    if (ssl_ == nullptr) return r;
    r.established = established_;
    r.client = ctx_->side() == TlsSide::Client;
    r.version = SSL_version(ssl_);
    r.cipher = ktls_cipher_of(ssl_);
    r.pending_input = BIO_ctrl_pending(in_) > 0 || SSL_has_pending(ssl_) != 0;
    r.pending_output = BIO_ctrl_pending(out_) > 0;
    if (ktls_) {
        r.peer_data_records = ktls_->data_records_read();
        r.key_updated = ktls_->key_updated();
        r.have_secrets = ktls_->have_secrets();
    }
    return r;
}

bool TlsSession::offload_params(KtlsParams& out) const noexcept {
    return ssl_ != nullptr && ktls_ && ktls_->derive(ssl_, out);
}

void free_tls_session(SSL_SESSION* session) noexcept {
    SSL_SESSION_free(session);
}

}  // namespace mbstorm::net
