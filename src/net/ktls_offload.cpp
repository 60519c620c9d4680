#include "net/ktls_offload.hpp"

#include <linux/tls.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <openssl/core_names.h>
#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <openssl/kdf.h>
#include <openssl/ssl.h>
#include <sys/socket.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <string_view>

#include "net/tls_session.hpp"

#ifndef SOL_TLS
#define SOL_TLS 282
#endif

namespace mbstorm::net {
namespace {

std::atomic<KtlsInstaller> test_installer{nullptr};

int tracker_index() noexcept {
    static const int index = SSL_get_ex_new_index(0, nullptr, nullptr, nullptr, nullptr);
    return index;
}

int hex_value(char c) noexcept {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

// Decodes `hex` into `out`; its size, or 0 when it is not hex or does not fit.
std::size_t from_hex(std::string_view hex, std::uint8_t* out, std::size_t capacity) noexcept {
    if (hex.size() % 2 != 0 || hex.size() / 2 > capacity) return 0;
    for (std::size_t i = 0; i < hex.size() / 2; ++i) {
        const int hi = hex_value(hex[2 * i]);
        const int lo = hex_value(hex[2 * i + 1]);
        if (hi < 0 || lo < 0) return 0;
        out[i] = static_cast<std::uint8_t>(hi << 4 | lo);
    }
    return hex.size() / 2;
}

bool kdf(const char* name, OSSL_PARAM* params, std::uint8_t* out, std::size_t size) noexcept {
    EVP_KDF* k = EVP_KDF_fetch(nullptr, name, nullptr);
    EVP_KDF_CTX* ctx = k == nullptr ? nullptr : EVP_KDF_CTX_new(k);
    const bool ok = ctx != nullptr && EVP_KDF_derive(ctx, out, size, params) == 1;
    EVP_KDF_CTX_free(ctx);
    EVP_KDF_free(k);
    return ok;
}

// RFC 8446 7.1: HKDF-Expand-Label(secret, label, "", size).
bool expand_label(const EVP_MD* md, const std::uint8_t* secret, std::size_t secret_size,
                  std::string_view label, std::uint8_t* out, std::size_t size) noexcept {
    static constexpr std::string_view kPrefix = "tls13 ";
    std::uint8_t info[2 + 1 + 255 + 1];
    std::size_t n = 0;
    info[n++] = static_cast<std::uint8_t>(size >> 8);
    info[n++] = static_cast<std::uint8_t>(size);
    info[n++] = static_cast<std::uint8_t>(kPrefix.size() + label.size());
    std::memcpy(info + n, kPrefix.data(), kPrefix.size());
    n += kPrefix.size();
    std::memcpy(info + n, label.data(), label.size());
    n += label.size();
    info[n++] = 0;  // empty context
    int mode = EVP_KDF_HKDF_MODE_EXPAND_ONLY;
    OSSL_PARAM params[] = {OSSL_PARAM_construct_utf8_string(
                               OSSL_KDF_PARAM_DIGEST, const_cast<char*>(EVP_MD_get0_name(md)), 0),
                           OSSL_PARAM_construct_int(OSSL_KDF_PARAM_MODE, &mode),
                           OSSL_PARAM_construct_octet_string(
                               OSSL_KDF_PARAM_KEY, const_cast<std::uint8_t*>(secret), secret_size),
                           OSSL_PARAM_construct_octet_string(OSSL_KDF_PARAM_INFO, info, n),
                           OSSL_PARAM_construct_end()};
    return kdf("HKDF", params, out, size);
}

bool tls13_keys(const EVP_MD* md, const std::uint8_t* secret, std::size_t secret_size,
                KtlsKeys& keys) noexcept {
    return expand_label(md, secret, secret_size, "key", keys.key.data(), keys.key_size) &&
           expand_label(md, secret, secret_size, "iv", keys.iv.data(), keys.iv.size());
}

void put_be64(std::uint8_t* out, std::uint64_t v) noexcept {
    for (int i = 7; i >= 0; --i, v >>= 8) out[i] = static_cast<std::uint8_t>(v);
}

// RFC 5246 6.3: the key block from the master secret; AEADs have no MAC keys. AES-GCM's
// implicit IV is 4 bytes (RFC 5288), ChaCha20-Poly1305's 12 (RFC 7905).
bool tls12_keys(SSL* ssl, const EVP_MD* md, KtlsCipher cipher, KtlsKeys& client,
                KtlsKeys& server) noexcept {
    std::uint8_t master[48];
    const std::size_t master_size =
        SSL_SESSION_get_master_key(SSL_get_session(ssl), master, sizeof master);
    std::uint8_t seed[13 + 2 * SSL3_RANDOM_SIZE];
    std::memcpy(seed, "key expansion", 13);
    if (master_size != sizeof master ||
        SSL_get_server_random(ssl, seed + 13, SSL3_RANDOM_SIZE) != SSL3_RANDOM_SIZE ||
        SSL_get_client_random(ssl, seed + 13 + SSL3_RANDOM_SIZE, SSL3_RANDOM_SIZE) !=
            SSL3_RANDOM_SIZE)
        return false;
    const std::size_t iv_size = cipher == KtlsCipher::Chacha20Poly1305 ? 12 : 4;
    const std::size_t k = client.key_size;
    std::uint8_t block[2 * 32 + 2 * 12];
    OSSL_PARAM params[] = {
        OSSL_PARAM_construct_utf8_string(OSSL_KDF_PARAM_DIGEST,
                                         const_cast<char*>(EVP_MD_get0_name(md)), 0),
        OSSL_PARAM_construct_octet_string(OSSL_KDF_PARAM_SECRET, master, master_size),
        OSSL_PARAM_construct_octet_string(OSSL_KDF_PARAM_SEED, seed, sizeof seed),
        OSSL_PARAM_construct_end()};
    const bool ok = kdf("TLS1-PRF", params, block, 2 * k + 2 * iv_size);
    if (ok) {
        std::memcpy(client.key.data(), block, k);
        std::memcpy(server.key.data(), block + k, k);
        std::memcpy(client.iv.data(), block + 2 * k, iv_size);
        std::memcpy(server.iv.data(), block + 2 * k + iv_size, iv_size);
    }
    OPENSSL_cleanse(master, sizeof master);
    OPENSSL_cleanse(block, sizeof block);
    return ok;
}

template <typename Info>
std::size_t fill(Info& info, int version, int type, const KtlsKeys& keys, std::uint8_t* out) {
    info.info.version = static_cast<decltype(info.info.version)>(version);
    info.info.cipher_type = static_cast<decltype(info.info.cipher_type)>(type);
    std::memcpy(info.key, keys.key.data(), sizeof info.key);
    // The kernel's salt || iv is the 12-byte nonce base (TLS 1.3) or implicit salt and
    // next explicit nonce (TLS 1.2): KtlsKeys::iv in both cases.
    std::memcpy(info.salt, keys.iv.data(), sizeof info.salt);
    std::memcpy(info.iv, keys.iv.data() + sizeof info.salt, sizeof info.iv);
    put_be64(info.rec_seq, keys.seq);
    std::memcpy(out, &info, sizeof info);
    OPENSSL_cleanse(&info, sizeof info);
    return sizeof info;
}

}  // namespace

const char* describe(KtlsRefusal refusal) noexcept {
    switch (refusal) {
        case KtlsRefusal::None:
            return "offloaded";
        case KtlsRefusal::Unavailable:
            return "the kernel has no TLS offload";
        case KtlsRefusal::DirectDescriptor:
            return "an io_uring direct descriptor";
        case KtlsRefusal::NotEstablished:
            return "the handshake is not over";
        case KtlsRefusal::Version:
            return "neither TLS 1.2 nor 1.3";
        case KtlsRefusal::Cipher:
            return "a cipher the kernel does not take";
        case KtlsRefusal::PendingInput:
            return "bytes buffered in OpenSSL";
        case KtlsRefusal::PendingOutput:
            return "ciphertext not yet sent";
        case KtlsRefusal::AwaitingPeerRecord:
            return "the server's tickets may still come";
        case KtlsRefusal::KeyUpdate:
            return "a TLS 1.3 key update";
        case KtlsRefusal::NoSecrets:
            return "no traffic secrets";
    }
    return "?";
}

KtlsRefusal ktls_decide(const KtlsReadiness& r) noexcept {
    if (!r.kernel_available) return KtlsRefusal::Unavailable;
    if (!r.real_fd) return KtlsRefusal::DirectDescriptor;
    if (!r.established) return KtlsRefusal::NotEstablished;
    if (r.version != TLS1_2_VERSION && r.version != TLS1_3_VERSION) return KtlsRefusal::Version;
    if (r.cipher == KtlsCipher::None) return KtlsRefusal::Cipher;
    if (r.key_updated) return KtlsRefusal::KeyUpdate;
    if (r.version == TLS1_3_VERSION && !r.have_secrets) return KtlsRefusal::NoSecrets;
    if (r.pending_input) return KtlsRefusal::PendingInput;
    if (r.pending_output) return KtlsRefusal::PendingOutput;
    // A TLS 1.3 server sends its NewSessionTickets after the handshake, before any answer
    // (how many, it does not say): once an answer is in, no ticket is left in flight.
    if (r.client && r.version == TLS1_3_VERSION && r.peer_data_records == 0)
        return KtlsRefusal::AwaitingPeerRecord;
    return KtlsRefusal::None;
}

void KtlsTracker::prepare_context(SSL_CTX* ctx) noexcept {
    tracker_index();  // allocated before any thread races for it
    SSL_CTX_set_keylog_callback(ctx, &KtlsTracker::on_keylog);
}

void KtlsTracker::attach(SSL* ssl) noexcept {
    SSL_set_ex_data(ssl, tracker_index(), this);
    SSL_set_msg_callback(ssl, &KtlsTracker::on_message);
    SSL_set_msg_callback_arg(ssl, this);
}

void KtlsTracker::on_message(int write_p, int, int content_type, const void* buf, std::size_t len,
                             SSL*, void* arg) {
    auto* t = static_cast<KtlsTracker*>(arg);
    const auto* bytes = static_cast<const std::uint8_t*>(buf);
    if (t == nullptr || len == 0) return;
    const int dir = write_p != 0 ? 1 : 0;
    if (content_type == SSL3_RT_HEADER) {
        // Each record costs a sequence number, except ChangeCipherSpec: in TLS 1.2 it
        // starts the protected records (numbered from 0); in TLS 1.3 it is unprotected
        // middlebox padding before the application keys exist.
        if (bytes[0] == SSL3_RT_CHANGE_CIPHER_SPEC)
            t->records_[dir] = 0;
        else
            ++t->records_[dir];
    } else if (content_type == SSL3_RT_INNER_CONTENT_TYPE) {
        if (dir == 0 && bytes[0] == SSL3_RT_APPLICATION_DATA) ++t->data_records_read_;
    } else if (content_type == SSL3_RT_HANDSHAKE && bytes[0] == SSL3_MT_KEY_UPDATE) {
        t->key_updated_ = true;
    }
}

void KtlsTracker::on_keylog(const SSL* ssl, const char* line) {
    auto* t = static_cast<KtlsTracker*>(SSL_get_ex_data(ssl, tracker_index()));
    if (t == nullptr) return;
    // "LABEL <client random> <secret>", both hex. Each application secret is logged when
    // this side installs it for its direction: that direction's count starts over.
    const std::string_view text(line);
    const std::size_t first = text.find(' ');
    const std::size_t second = first == std::string_view::npos ? first : text.find(' ', first + 1);
    if (second == std::string_view::npos) return;
    const std::string_view label = text.substr(0, first);
    const std::string_view secret = text.substr(second + 1);
    const bool server = SSL_is_server(const_cast<SSL*>(ssl)) != 0;
    if (label == "CLIENT_TRAFFIC_SECRET_0") {
        t->client_secret_size_ = from_hex(secret, t->client_secret_.data(), 48);
        t->records_[server ? 0 : 1] = 0;
    } else if (label == "SERVER_TRAFFIC_SECRET_0") {
        t->server_secret_size_ = from_hex(secret, t->server_secret_.data(), 48);
        t->records_[server ? 1 : 0] = 0;
    }
}

KtlsCipher ktls_cipher_of(const SSL* ssl) noexcept {
    const SSL_CIPHER* c = SSL_get_current_cipher(ssl);
    if (c == nullptr) return KtlsCipher::None;
    switch (SSL_CIPHER_get_cipher_nid(c)) {
        case NID_aes_128_gcm:
            return KtlsCipher::Aes128Gcm;
        case NID_aes_256_gcm:
            return KtlsCipher::Aes256Gcm;
        case NID_chacha20_poly1305:
            return KtlsCipher::Chacha20Poly1305;
        default:
            return KtlsCipher::None;
    }
}

bool KtlsTracker::derive(SSL* ssl, KtlsParams& out) const noexcept {
    out = KtlsParams{};
    out.version = SSL_version(ssl);
    out.cipher = ktls_cipher_of(ssl);
    const SSL_CIPHER* c = SSL_get_current_cipher(ssl);
    const EVP_MD* md = c == nullptr ? nullptr : SSL_CIPHER_get_handshake_digest(c);
    if (out.cipher == KtlsCipher::None || md == nullptr) return false;
    const std::size_t key_size = out.cipher == KtlsCipher::Aes128Gcm ? 16 : 32;
    KtlsKeys client;
    KtlsKeys server;
    client.key_size = server.key_size = key_size;
    bool ok = false;
    if (out.version == TLS1_3_VERSION) {
        ok = have_secrets() && tls13_keys(md, client_secret_.data(), client_secret_size_, client) &&
             tls13_keys(md, server_secret_.data(), server_secret_size_, server);
    } else if (out.version == TLS1_2_VERSION) {
        ok = tls12_keys(ssl, md, out.cipher, client, server);
    }
    const bool is_server = SSL_is_server(ssl) != 0;
    out.tx = is_server ? server : client;
    out.rx = is_server ? client : server;
    out.tx.seq = records_[1];
    out.rx.seq = records_[0];
    if (out.version == TLS1_2_VERSION && out.cipher != KtlsCipher::Chacha20Poly1305) {
        // The explicit nonce only has to be unique per key: the sequence number is (OpenSSL's
        // own counter started at a random 64-bit value, so the two never meet in practice).
        put_be64(out.tx.iv.data() + 4, out.tx.seq);
        put_be64(out.rx.iv.data() + 4, out.rx.seq);
    }
    OPENSSL_cleanse(&client, sizeof client);
    OPENSSL_cleanse(&server, sizeof server);
    if (!ok) OPENSSL_cleanse(&out, sizeof out);
    return ok;
}

std::size_t ktls_crypto_info(int version, KtlsCipher cipher, const KtlsKeys& keys,
                             std::uint8_t* out) noexcept {
    switch (cipher) {
        case KtlsCipher::Aes128Gcm: {
            tls12_crypto_info_aes_gcm_128 info{};
            return fill(info, version, TLS_CIPHER_AES_GCM_128, keys, out);
        }
        case KtlsCipher::Aes256Gcm: {
            tls12_crypto_info_aes_gcm_256 info{};
            return fill(info, version, TLS_CIPHER_AES_GCM_256, keys, out);
        }
        case KtlsCipher::Chacha20Poly1305: {
            tls12_crypto_info_chacha20_poly1305 info{};  // no salt: the IV is all 12 bytes
            info.info.version = static_cast<decltype(info.info.version)>(version);
            info.info.cipher_type = TLS_CIPHER_CHACHA20_POLY1305;
            std::memcpy(info.key, keys.key.data(), sizeof info.key);
            std::memcpy(info.iv, keys.iv.data(), sizeof info.iv);
            put_be64(info.rec_seq, keys.seq);
            std::memcpy(out, &info, sizeof info);
            OPENSSL_cleanse(&info, sizeof info);
            return sizeof info;
        }
        case KtlsCipher::None:
            break;
    }
    return 0;
}

void set_ktls_installer_for_testing(KtlsInstaller installer) noexcept {
    test_installer.store(installer, std::memory_order_relaxed);
}

int install_ktls(int fd, const KtlsParams& params, bool& changed) noexcept {
    static constexpr char kUlp[] = "tls";
    std::uint8_t info[kKtlsCryptoInfoMax];
    changed = false;
    if (KtlsInstaller fake = test_installer.load(std::memory_order_relaxed)) {
        try {
            return fake(fd, params, changed);
        } catch (...) {
            return -EINVAL;
        }
    }
    if (::setsockopt(fd, SOL_TCP, TCP_ULP, kUlp, sizeof kUlp - 1) != 0) return -errno;
    std::size_t size = ktls_crypto_info(params.version, params.cipher, params.tx, info);
    if (size == 0) return -EINVAL;
    int rc = ::setsockopt(fd, SOL_TLS, TLS_TX, info, static_cast<socklen_t>(size));
    if (rc == 0) {
        changed = true;
        size = ktls_crypto_info(params.version, params.cipher, params.rx, info);
        rc = ::setsockopt(fd, SOL_TLS, TLS_RX, info, static_cast<socklen_t>(size));
    }
    const int error = rc == 0 ? 0 : -errno;
    OPENSSL_cleanse(info, sizeof info);
    return error;
}

KtlsHandOffResult ktls_hand_off(const TlsSession& session, int fd, bool real_fd) noexcept {
    KtlsReadiness r = session.offload_readiness();
    r.kernel_available = true;
    r.real_fd = real_fd;
    switch (ktls_decide(r)) {
        case KtlsRefusal::None:
            break;
        case KtlsRefusal::PendingInput:
        case KtlsRefusal::PendingOutput:
        case KtlsRefusal::AwaitingPeerRecord:
            return KtlsHandOffResult::Later;
        default:
            return KtlsHandOffResult::Userspace;
    }
    KtlsParams params;
    if (!session.offload_params(params)) return KtlsHandOffResult::Userspace;
    bool changed = false;
    if (install_ktls(fd, params, changed) != 0)
        return changed ? KtlsHandOffResult::Broken : KtlsHandOffResult::Userspace;
    return KtlsHandOffResult::Done;
}

}  // namespace mbstorm::net
