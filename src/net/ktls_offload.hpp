// Handing a TLS connection's record layer to the kernel (kTLS) once OpenSSL has finished the
// handshake: the keys, IVs and record sequence numbers each direction has reached, derived
// from OpenSSL's state, and the setsockopt calls that install them. After the hand-off the
// socket carries plaintext both ways and io_uring moves it like plain TCP.
//
// OpenSSL does not expose its record sequence numbers, so a KtlsTracker attached to the
// session before the handshake counts the records of each direction since its last key
// change, and keeps the TLS 1.3 traffic secrets from the keylog callback.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

using SSL = struct ssl_st;
using SSL_CTX = struct ssl_ctx_st;

namespace mbstorm::net {

// The AEADs the kernel's <linux/tls.h> takes that OpenSSL negotiates.
enum class KtlsCipher : unsigned char { None, Aes128Gcm, Aes256Gcm, Chacha20Poly1305 };

// One direction's record protection at the hand-off.
struct KtlsKeys {
    std::array<std::uint8_t, 32> key{};
    std::size_t key_size = 0;
    // TLS 1.3 and ChaCha20-Poly1305: the 12-byte static IV (the nonce is IV XOR sequence).
    // TLS 1.2 AES-GCM: the 4-byte salt, then the 8-byte explicit nonce of the next record.
    std::array<std::uint8_t, 12> iv{};
    std::uint64_t seq = 0;  // sequence number of the next record
};

struct KtlsParams {
    int version = 0;  // TLS1_2_VERSION or TLS1_3_VERSION
    KtlsCipher cipher = KtlsCipher::None;
    KtlsKeys tx;  // what this side sends
    KtlsKeys rx;  // what this side receives
};

// Why a connection stays in userspace; None: it can be handed off now.
enum class KtlsRefusal : unsigned char {
    None,
    Unavailable,       // the kernel has no TLS offload (the probe failed)
    DirectDescriptor,  // io_uring direct descriptors cannot take setsockopt
    NotEstablished,
    Version,             // neither TLS 1.2 nor 1.3
    Cipher,              // an AEAD the kernel does not take (or none)
    PendingInput,        // ciphertext or plaintext OpenSSL holds that the kernel would not see
    PendingOutput,       // ciphertext not yet on the wire (it must precede the kernel's)
    AwaitingPeerRecord,  // TLS 1.3 client: the server's tickets may still be coming
    KeyUpdate,           // keys changed after the handshake: the secrets are stale
    NoSecrets,           // the tracker was attached too late or the derivation failed
};

const char* describe(KtlsRefusal refusal) noexcept;

// What the decision rests on (filled from a session; a plain struct so it is testable).
struct KtlsReadiness {
    bool kernel_available = false;
    bool real_fd = false;
    bool established = false;
    bool client = false;
    int version = 0;
    KtlsCipher cipher = KtlsCipher::None;
    bool pending_input = false;
    bool pending_output = false;
    std::uint64_t peer_data_records = 0;  // application-data records received (TLS 1.3)
    bool key_updated = false;
    bool have_secrets = false;
};

KtlsRefusal ktls_decide(const KtlsReadiness& r) noexcept;

// Attached to one SSL before its handshake (see the file comment).
class KtlsTracker {
  public:
    // The keylog callback is the context's: set it once, before the context is shared by
    // threads (it finds each connection's tracker through its SSL).
    static void prepare_context(SSL_CTX* ctx) noexcept;
    // Installs the record callbacks on `ssl`, before its handshake.
    void attach(SSL* ssl) noexcept;

    std::uint64_t records(bool write) const noexcept { return records_[write ? 1 : 0]; }
    // TLS 1.3 application-data records received (not tickets, not key updates).
    std::uint64_t data_records_read() const noexcept { return data_records_read_; }
    bool key_updated() const noexcept { return key_updated_; }
    bool have_secrets() const noexcept {
        return client_secret_size_ > 0 && server_secret_size_ > 0;
    }

    // The parameters of `ssl` (which this tracker watched) at this moment. False when the
    // version or cipher is not offloadable or a derivation step failed.
    bool derive(SSL* ssl, KtlsParams& out) const noexcept;

  private:
    static void on_message(int write_p, int version, int content_type, const void* buf,
                           std::size_t len, SSL* ssl, void* arg);
    static void on_keylog(const SSL* ssl, const char* line);

    std::array<std::uint64_t, 2> records_{};  // [read, write]: since the last key change
    std::uint64_t data_records_read_ = 0;
    bool key_updated_ = false;
    std::array<std::uint8_t, 48> client_secret_{};
    std::array<std::uint8_t, 48> server_secret_{};
    std::size_t client_secret_size_ = 0;
    std::size_t server_secret_size_ = 0;
};

KtlsCipher ktls_cipher_of(const SSL* ssl) noexcept;

// The kernel's struct tls12_crypto_info_* for one direction, written to `out` (at least
// kKtlsCryptoInfoMax bytes); returns its size, 0 for KtlsCipher::None.
inline constexpr std::size_t kKtlsCryptoInfoMax = 64;
std::size_t ktls_crypto_info(int version, KtlsCipher cipher, const KtlsKeys& keys,
                             std::uint8_t* out) noexcept;

// TCP_ULP "tls", then SOL_TLS TLS_TX and TLS_RX on `fd`: 0, or -errno. `changed` says
// whether TX was installed: if so (and RX failed) the connection cannot go on and must
// close; if not, the socket still passes OpenSSL's ciphertext through unchanged.
int install_ktls(int fd, const KtlsParams& params, bool& changed) noexcept;

class TlsSession;

// What one try at handing a connection to the kernel came to.
enum class KtlsHandOffResult : unsigned char {
    Later,      // not at this moment (bytes in OpenSSL, the peer's tickets): try at the next input
    Userspace,  // never for this connection: OpenSSL keeps its records
    Done,       // the kernel has the record layer both ways: the socket carries plaintext
    // The kernel took the send side and refused the receive side: the connection cannot go
    // on. A kernel that does this would do it to every connection: hand off no more.
    Broken,
};

// The hand-off of `session`, established on socket `fd`, when the kernel can take it now
// (ktls_decide, offload_params, install_ktls). The caller has checked that the kernel has the
// offload and that none of the connection's bytes are in flight either way; real_fd: false
// for an io_uring direct descriptor (setsockopt cannot reach it).
KtlsHandOffResult ktls_hand_off(const TlsSession& session, int fd, bool real_fd) noexcept;

// Tests only: install_ktls calls `installer` instead (nullptr: the kernel again).
using KtlsInstaller = int (*)(int fd, const KtlsParams& params, bool& changed);
void set_ktls_installer_for_testing(KtlsInstaller installer) noexcept;

}  // namespace mbstorm::net
