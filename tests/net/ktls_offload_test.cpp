// The kernel TLS hand-off's parameters are exact, proved without the kernel: a live OpenSSL
// client and server over memory BIOs (TLS 1.3 and 1.2, each AEAD the kernel takes), the
// parameters derived as the hand-off would, then (a) the next record OpenSSL sends decrypted
// here with them and (b) a record sealed here with them, as the kernel would seal it,
// accepted by the peer's OpenSSL. Plus the decision that keeps a connection in userspace.
#include <gtest/gtest.h>
#include <linux/tls.h>
#include <netinet/in.h>
#include <openssl/evp.h>
#include <openssl/ssl.h>

#include <cerrno>
#include <cstring>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "../support/tls_test_support.hpp"
#include "net/kernel_tls.hpp"
#include "net/ktls_offload.hpp"
#include "net/socket.hpp"
#include "net/tls_context.hpp"
#include "net/tls_session.hpp"

namespace mbstorm::net {
namespace {

using Bytes = std::vector<std::uint8_t>;

Bytes bytes_of(const std::string& s) {
    return Bytes(s.begin(), s.end());
}

const EVP_CIPHER* aead(KtlsCipher c) {
    switch (c) {
        case KtlsCipher::Aes128Gcm:
            return EVP_aes_128_gcm();
        case KtlsCipher::Aes256Gcm:
            return EVP_aes_256_gcm();
        case KtlsCipher::Chacha20Poly1305:
            return EVP_chacha20_poly1305();
        case KtlsCipher::None:
            break;
    }
    return nullptr;
}

void put_be64(std::uint8_t* out, std::uint64_t v) {
    for (int i = 7; i >= 0; --i, v >>= 8) out[i] = static_cast<std::uint8_t>(v);
}

// The per-record nonce: salt || explicit nonce (TLS 1.2 AES-GCM, RFC 5288), otherwise the
// static IV XOR the sequence number padded to 12 bytes (RFC 8446 5.3, RFC 7905).
void nonce_for(const KtlsParams& p, const KtlsKeys& k, std::uint64_t seq,
               const std::uint8_t* explicit_nonce, std::uint8_t* nonce) {
    std::memcpy(nonce, k.iv.data(), 12);
    if (p.version == TLS1_2_VERSION && p.cipher != KtlsCipher::Chacha20Poly1305) {
        std::memcpy(nonce + 4, explicit_nonce, 8);
        return;
    }
    std::uint8_t s[8];
    put_be64(s, seq);
    for (int i = 0; i < 8; ++i) nonce[4 + i] ^= s[i];
}

bool explicit_nonce(const KtlsParams& p) {
    return p.version == TLS1_2_VERSION && p.cipher != KtlsCipher::Chacha20Poly1305;
}

// TLS 1.2's AAD: seq || type || version || plaintext length.
Bytes tls12_aad(std::uint64_t seq, std::uint8_t type, std::size_t length) {
    Bytes aad(13);
    put_be64(aad.data(), seq);
    aad[8] = type;
    aad[9] = 3;
    aad[10] = 3;
    aad[11] = static_cast<std::uint8_t>(length >> 8);
    aad[12] = static_cast<std::uint8_t>(length);
    return aad;
}

// One application-data record as the kernel would seal it with `k` at sequence k.seq.
Bytes seal(const KtlsParams& p, const KtlsKeys& k, const Bytes& plain) {
    const bool tls13 = p.version == TLS1_3_VERSION;
    Bytes inner = plain;
    if (tls13) inner.push_back(23);  // the inner content type
    const std::size_t prefix = explicit_nonce(p) ? 8 : 0;
    const std::size_t body = prefix + inner.size() + 16;
    Bytes record = {23, 3, 3, static_cast<std::uint8_t>(body >> 8),
                    static_cast<std::uint8_t>(body)};
    if (prefix) record.insert(record.end(), k.iv.begin() + 4, k.iv.end());
    std::uint8_t nonce[12];
    nonce_for(p, k, k.seq, k.iv.data() + 4, nonce);
    const Bytes aad = tls13 ? record : tls12_aad(k.seq, 23, plain.size());
    EVP_CIPHER_CTX* ctx = EVP_CIPHER_CTX_new();
    int n = 0;
    Bytes out(inner.size() + 16);
    EXPECT_EQ(EVP_EncryptInit_ex(ctx, aead(p.cipher), nullptr, nullptr, nullptr), 1);
    EXPECT_EQ(EVP_CIPHER_CTX_ctrl(ctx, EVP_CTRL_AEAD_SET_IVLEN, 12, nullptr), 1);
    EXPECT_EQ(EVP_EncryptInit_ex(ctx, nullptr, nullptr, k.key.data(), nonce), 1);
    EXPECT_EQ(EVP_EncryptUpdate(ctx, nullptr, &n, aad.data(), static_cast<int>(aad.size())), 1);
    EXPECT_EQ(EVP_EncryptUpdate(ctx, out.data(), &n, inner.data(), static_cast<int>(inner.size())),
              1);
    EXPECT_EQ(EVP_EncryptFinal_ex(ctx, out.data() + n, &n), 1);
    EXPECT_EQ(EVP_CIPHER_CTX_ctrl(ctx, EVP_CTRL_AEAD_GET_TAG, 16, out.data() + inner.size()), 1);
    EVP_CIPHER_CTX_free(ctx);
    record.insert(record.end(), out.begin(), out.end());
    return record;
}

// Opens the one record in `record` with `k` at sequence k.seq; the plaintext, or "" (and a
// failure) when it does not verify.
Bytes open_record(const KtlsParams& p, const KtlsKeys& k, const Bytes& record) {
    const bool tls13 = p.version == TLS1_3_VERSION;
    EXPECT_GE(record.size(), 5u + 16u);
    if (record.size() < 5 + 16) return {};
    EXPECT_EQ(record[0], 23);  // application data (TLS 1.3: the outer type of every record)
    const std::size_t body = static_cast<std::size_t>(record[3] << 8 | record[4]);
    EXPECT_EQ(record.size(), 5 + body) << "exactly one record";
    const std::size_t prefix = explicit_nonce(p) ? 8 : 0;
    const std::uint8_t* ct = record.data() + 5 + prefix;
    const std::size_t ct_size = body - prefix - 16;
    std::uint8_t nonce[12];
    nonce_for(p, k, k.seq, record.data() + 5, nonce);
    const Bytes aad =
        tls13 ? Bytes(record.begin(), record.begin() + 5) : tls12_aad(k.seq, record[0], ct_size);
    EVP_CIPHER_CTX* ctx = EVP_CIPHER_CTX_new();
    int n = 0;
    Bytes out(ct_size + 16);
    EXPECT_EQ(EVP_DecryptInit_ex(ctx, aead(p.cipher), nullptr, nullptr, nullptr), 1);
    EXPECT_EQ(EVP_CIPHER_CTX_ctrl(ctx, EVP_CTRL_AEAD_SET_IVLEN, 12, nullptr), 1);
    EXPECT_EQ(EVP_DecryptInit_ex(ctx, nullptr, nullptr, k.key.data(), nonce), 1);
    EXPECT_EQ(EVP_DecryptUpdate(ctx, nullptr, &n, aad.data(), static_cast<int>(aad.size())), 1);
    EXPECT_EQ(EVP_DecryptUpdate(ctx, out.data(), &n, ct, static_cast<int>(ct_size)), 1);
    EXPECT_EQ(EVP_CIPHER_CTX_ctrl(ctx, EVP_CTRL_AEAD_SET_TAG, 16,
                                  const_cast<std::uint8_t*>(ct + ct_size)),
              1);
    int last = 0;
    const bool verified = EVP_DecryptFinal_ex(ctx, out.data() + n, &last) == 1;
    EVP_CIPHER_CTX_free(ctx);
    EXPECT_TRUE(verified) << "the record does not open with the derived parameters";
    if (!verified) return {};
    out.resize(ct_size);
    if (tls13) {
        EXPECT_FALSE(out.empty());
        if (out.empty()) return {};
        EXPECT_EQ(out.back(), 23) << "inner content type";
        out.pop_back();
    }
    return out;
}

void expect_same(const KtlsKeys& a, const KtlsKeys& b, const char* what) {
    EXPECT_EQ(a.key_size, b.key_size) << what;
    EXPECT_EQ(a.key, b.key) << what;
    EXPECT_EQ(a.iv, b.iv) << what;
    EXPECT_EQ(a.seq, b.seq) << what;
}

using test::drain;
using test::pump;

class KtlsOffloadTest : public test::TlsCertsTest {
  protected:
    // Contexts limited to one version and one cipher, tracked for the hand-off.
    static std::shared_ptr<TlsContext> context(TlsSide side, int version, const char* cipher,
                                               int tickets = -1) {
        const bool server = side == TlsSide::Server;
        auto ctx = TlsCertsTest::context(side, server ? "server" : "operator", version);
        if (!ctx) return ctx;
        SSL_CTX_set_min_proto_version(ctx->get(), version);
        if (version == TLS1_3_VERSION)
            EXPECT_EQ(SSL_CTX_set_ciphersuites(ctx->get(), cipher), 1);
        else
            EXPECT_EQ(SSL_CTX_set_cipher_list(ctx->get(), cipher), 1);
        if (server && tickets >= 0) SSL_CTX_set_num_tickets(ctx->get(), tickets);
        KtlsTracker::prepare_context(ctx->get());
        return ctx;
    }
    // `from` encrypts `text` with OpenSSL; its one record goes to `to`, which must read it.
    static Bytes send_via_openssl(TlsSession& from, TlsSession& to, const std::string& text) {
        const Bytes plain = bytes_of(text);
        EXPECT_EQ(from.write(plain.data(), plain.size()), TlsStatus::Ok);
        Bytes record;
        from.take_output(record);
        to.feed(record.data(), record.size());
        EXPECT_EQ(drain(to), plain);
        return record;
    }
};

struct Case {
    int version;
    const char* cipher;
    KtlsCipher expected;
    int tickets;          // server's NewSessionTickets (TLS 1.3), -1: OpenSSL's default
    bool resume = false;  // the handshake resumes the session of an earlier one
};

void PrintTo(const Case& c, std::ostream* os) {
    *os << c.cipher << " tickets " << c.tickets << (c.resume ? " resumed" : "");
}

class KtlsHandOff : public KtlsOffloadTest, public ::testing::WithParamInterface<Case> {};

TEST_P(KtlsHandOff, DerivedParametersOpenOpenSslsRecordsAndSealRecordsItAccepts) {
    const Case& tc = GetParam();
    auto server_ctx = context(TlsSide::Server, tc.version, tc.cipher, tc.tickets);
    auto client_ctx = context(TlsSide::Client, tc.version, tc.cipher);
    SSL_SESSION* saved = nullptr;
    if (tc.resume) {
        TlsSession s0(server_ctx);
        TlsSession c0(client_ctx);
        pump(c0, s0);
        drain(c0);
        saved = c0.saved_session();
        ASSERT_NE(saved, nullptr);
    }
    TlsSession s(server_ctx);
    TlsSession c(client_ctx, saved);
    if (saved != nullptr) free_tls_session(saved);
    s.track_for_offload();
    c.track_for_offload();
    pump(c, s);
    ASSERT_TRUE(c.established()) << c.error();
    ASSERT_TRUE(s.established()) << s.error();
    EXPECT_EQ(s.resumed(), tc.resume);
    drain(c);  // TLS 1.3: the server's tickets, sent after its handshake

    // A few records each way under OpenSSL first: the hand-off happens mid-stream.
    for (int i = 0; i < 3; ++i) {
        send_via_openssl(c, s, "request " + std::to_string(i));
        send_via_openssl(s, c, "answer " + std::to_string(i));
    }

    KtlsParams sp;
    KtlsParams cp;
    ASSERT_TRUE(s.offload_params(sp));
    ASSERT_TRUE(c.offload_params(cp));
    EXPECT_EQ(sp.cipher, tc.expected);
    EXPECT_EQ(sp.version, tc.version);
    EXPECT_EQ(sp.tx.key_size, tc.expected == KtlsCipher::Aes128Gcm ? 16u : 32u);
    // What one side sends, the other receives: derived independently, they must agree.
    expect_same(sp.tx, cp.rx, "server to client");
    expect_same(sp.rx, cp.tx, "client to server");
    // The sequence numbers the records so far have used up.
    const std::uint64_t tickets = tc.version == TLS1_3_VERSION
                                      ? static_cast<std::uint64_t>(tc.tickets < 0 ? 2 : tc.tickets)
                                      : 0;
    const std::uint64_t finished = tc.version == TLS1_2_VERSION ? 1 : 0;
    // (After a TLS 1.3 resumption the tickets are OpenSSL's choice: not predicted.)
    if (!(tc.resume && tc.version == TLS1_3_VERSION)) {
        EXPECT_EQ(sp.tx.seq, finished + tickets + 3);
    }
    EXPECT_EQ(cp.tx.seq, finished + 3);

    // (a) The next records OpenSSL seals open with the derived parameters.
    EXPECT_EQ(open_record(sp, sp.tx, send_via_openssl(s, c, "answer 3")), bytes_of("answer 3"));
    EXPECT_EQ(open_record(cp, cp.tx, send_via_openssl(c, s, "request 3")), bytes_of("request 3"));

    // (b) Records sealed here as the kernel would, at the sequence numbers reached now, are
    // accepted by the peer's OpenSSL (and a second one: the numbers go on from there).
    ASSERT_TRUE(s.offload_params(sp));
    ASSERT_TRUE(c.offload_params(cp));
    for (int i = 4; i < 6; ++i) {
        const Bytes request = bytes_of("request " + std::to_string(i));
        const Bytes sealed = seal(cp, cp.tx, request);
        s.feed(sealed.data(), sealed.size());
        EXPECT_EQ(drain(s), request) << "the server's OpenSSL refused the client's kTLS record";
        const Bytes answer = bytes_of("answer " + std::to_string(i));
        const Bytes back = seal(sp, sp.tx, answer);
        c.feed(back.data(), back.size());
        EXPECT_EQ(drain(c), answer) << "the client's OpenSSL refused the server's kTLS record";
        ++cp.tx.seq;
        ++sp.tx.seq;
        if (explicit_nonce(sp)) {
            put_be64(cp.tx.iv.data() + 4, cp.tx.seq);
            put_be64(sp.tx.iv.data() + 4, sp.tx.seq);
        }
    }

    // The kernel's crypto_info carries them field by field.
    std::uint8_t info[kKtlsCryptoInfoMax];
    const std::size_t size = ktls_crypto_info(sp.version, sp.cipher, sp.tx, info);
    std::uint8_t seq[8];
    put_be64(seq, sp.tx.seq);
    if (sp.cipher == KtlsCipher::Chacha20Poly1305) {
        tls12_crypto_info_chacha20_poly1305 ci;
        ASSERT_EQ(size, sizeof ci);
        std::memcpy(&ci, info, sizeof ci);
        EXPECT_EQ(ci.info.version, sp.version);
        EXPECT_EQ(ci.info.cipher_type, TLS_CIPHER_CHACHA20_POLY1305);
        EXPECT_EQ(std::memcmp(ci.key, sp.tx.key.data(), 32), 0);
        EXPECT_EQ(std::memcmp(ci.iv, sp.tx.iv.data(), 12), 0);
        EXPECT_EQ(std::memcmp(ci.rec_seq, seq, 8), 0);
    } else {
        // AES-128 and AES-256 share the layout but for the key's size.
        tls12_crypto_info_aes_gcm_256 ci{};
        const std::size_t key = sp.tx.key_size;
        ASSERT_EQ(size, sizeof(tls_crypto_info) + 8 + key + 4 + 8);
        std::memcpy(&ci.info, info, sizeof ci.info);
        EXPECT_EQ(ci.info.version, sp.version);
        EXPECT_EQ(ci.info.cipher_type, key == 16 ? TLS_CIPHER_AES_GCM_128 : TLS_CIPHER_AES_GCM_256);
        const std::uint8_t* p = info + sizeof ci.info;
        EXPECT_EQ(std::memcmp(p, sp.tx.iv.data() + 4, 8), 0) << "iv";
        EXPECT_EQ(std::memcmp(p + 8, sp.tx.key.data(), key), 0) << "key";
        EXPECT_EQ(std::memcmp(p + 8 + key, sp.tx.iv.data(), 4), 0) << "salt";
        EXPECT_EQ(std::memcmp(p + 8 + key + 4, seq, 8), 0) << "rec_seq";
    }
}

INSTANTIATE_TEST_SUITE_P(
    EachVersionAndCipher, KtlsHandOff,
    ::testing::Values(
        Case{TLS1_3_VERSION, "TLS_AES_128_GCM_SHA256", KtlsCipher::Aes128Gcm, -1},
        Case{TLS1_3_VERSION, "TLS_AES_256_GCM_SHA384", KtlsCipher::Aes256Gcm, -1},
        Case{TLS1_3_VERSION, "TLS_CHACHA20_POLY1305_SHA256", KtlsCipher::Chacha20Poly1305, -1},
        Case{TLS1_3_VERSION, "TLS_AES_128_GCM_SHA256", KtlsCipher::Aes128Gcm, 0},
        Case{TLS1_3_VERSION, "TLS_AES_256_GCM_SHA384", KtlsCipher::Aes256Gcm, 5},
        Case{TLS1_2_VERSION, "ECDHE-ECDSA-AES128-GCM-SHA256", KtlsCipher::Aes128Gcm, -1},
        Case{TLS1_2_VERSION, "ECDHE-ECDSA-AES256-GCM-SHA384", KtlsCipher::Aes256Gcm, -1},
        Case{TLS1_2_VERSION, "ECDHE-ECDSA-CHACHA20-POLY1305", KtlsCipher::Chacha20Poly1305, -1},
        Case{TLS1_3_VERSION, "TLS_AES_128_GCM_SHA256", KtlsCipher::Aes128Gcm, -1, true},
        Case{TLS1_2_VERSION, "ECDHE-ECDSA-AES128-GCM-SHA256", KtlsCipher::Aes128Gcm, -1, true}),
    [](const ::testing::TestParamInfo<Case>& info) {
        const Case& c = info.param;
        std::string name = c.version == TLS1_3_VERSION ? "Tls13_" : "Tls12_";
        name += c.expected == KtlsCipher::Aes128Gcm   ? "Aes128Gcm"
                : c.expected == KtlsCipher::Aes256Gcm ? "Aes256Gcm"
                                                      : "Chacha20Poly1305";
        if (c.tickets >= 0) name += "_" + std::to_string(c.tickets) + "Tickets";
        if (c.resume) name += "_Resumed";
        return name;
    });

// Everything that keeps a connection in userspace, in the order the decision checks it.
TEST(KtlsDecision, EachReasonKeepsTheConnectionInUserspace) {
    KtlsReadiness ready;
    ready.kernel_available = true;
    ready.real_fd = true;
    ready.established = true;
    ready.client = true;
    ready.version = TLS1_3_VERSION;
    ready.cipher = KtlsCipher::Aes128Gcm;
    ready.peer_data_records = 1;
    ready.have_secrets = true;
    EXPECT_EQ(ktls_decide(ready), KtlsRefusal::None);

    auto with = [&](auto change) {
        KtlsReadiness r = ready;
        change(r);
        return ktls_decide(r);
    };
    EXPECT_EQ(with([](KtlsReadiness& r) { r.kernel_available = false; }), KtlsRefusal::Unavailable);
    EXPECT_EQ(with([](KtlsReadiness& r) { r.real_fd = false; }), KtlsRefusal::DirectDescriptor);
    EXPECT_EQ(with([](KtlsReadiness& r) { r.established = false; }), KtlsRefusal::NotEstablished);
    EXPECT_EQ(with([](KtlsReadiness& r) { r.version = TLS1_1_VERSION; }), KtlsRefusal::Version);
    EXPECT_EQ(with([](KtlsReadiness& r) { r.cipher = KtlsCipher::None; }), KtlsRefusal::Cipher);
    EXPECT_EQ(with([](KtlsReadiness& r) { r.key_updated = true; }), KtlsRefusal::KeyUpdate);
    EXPECT_EQ(with([](KtlsReadiness& r) { r.have_secrets = false; }), KtlsRefusal::NoSecrets);
    EXPECT_EQ(with([](KtlsReadiness& r) { r.pending_input = true; }), KtlsRefusal::PendingInput);
    EXPECT_EQ(with([](KtlsReadiness& r) { r.pending_output = true; }), KtlsRefusal::PendingOutput);
    EXPECT_EQ(with([](KtlsReadiness& r) { r.peer_data_records = 0; }),
              KtlsRefusal::AwaitingPeerRecord);
    // A server (or TLS 1.2, whose tickets precede the Finished) need not wait for a record.
    EXPECT_EQ(with([](KtlsReadiness& r) { r.peer_data_records = 0, r.client = false; }),
              KtlsRefusal::None);
    EXPECT_EQ(with([](KtlsReadiness& r) {
                  r.peer_data_records = 0, r.version = TLS1_2_VERSION, r.have_secrets = false;
              }),
              KtlsRefusal::None);
    for (int i = 0; i <= static_cast<int>(KtlsRefusal::NoSecrets); ++i)
        EXPECT_STRNE(describe(static_cast<KtlsRefusal>(i)), "?");
}

// The readiness a live session reports: what OpenSSL still holds, the cipher, the tickets.
TEST_F(KtlsOffloadTest, ALiveSessionReportsWhatKeepsItInUserspace) {
    auto decide = [](const TlsSession& session) {
        KtlsReadiness r = session.offload_readiness();
        r.kernel_available = r.real_fd = true;
        return ktls_decide(r);
    };
    {
        TlsSession s(context(TlsSide::Server, TLS1_3_VERSION, "TLS_AES_128_GCM_SHA256"));
        TlsSession c(context(TlsSide::Client, TLS1_3_VERSION, "TLS_AES_128_GCM_SHA256"));
        s.track_for_offload();
        c.track_for_offload();
        EXPECT_EQ(decide(s), KtlsRefusal::NotEstablished);
        pump(c, s);
        ASSERT_TRUE(s.established()) << s.error();
        // The client has the tickets' ciphertext unread; once read, more could still come
        // (the server does not say how many): only an answer proves they are all in.
        EXPECT_EQ(decide(c), KtlsRefusal::PendingInput);
        drain(c);
        EXPECT_EQ(decide(c), KtlsRefusal::AwaitingPeerRecord);
        EXPECT_EQ(decide(s), KtlsRefusal::None);
        send_via_openssl(s, c, "answer");
        EXPECT_EQ(decide(c), KtlsRefusal::None);
        // Written but not yet sent, and received but not yet read.
        const Bytes request = bytes_of("request");
        ASSERT_EQ(c.write(request.data(), request.size()), TlsStatus::Ok);
        EXPECT_EQ(decide(c), KtlsRefusal::PendingOutput);
        Bytes record;
        c.take_output(record);
        s.feed(record.data(), record.size());
        EXPECT_EQ(decide(s), KtlsRefusal::PendingInput);
        // Plaintext OpenSSL decrypted but the caller has not taken yet.
        std::uint8_t one = 0;
        std::size_t n = 0;
        ASSERT_EQ(s.read(&one, 1, n), TlsStatus::Ok);
        EXPECT_EQ(decide(s), KtlsRefusal::PendingInput);
        drain(s);
        EXPECT_EQ(decide(s), KtlsRefusal::None);
    }
    {
        // No tickets: the client waits for the first answer before it may hand off.
        TlsSession s(context(TlsSide::Server, TLS1_3_VERSION, "TLS_AES_128_GCM_SHA256", 0));
        TlsSession c(context(TlsSide::Client, TLS1_3_VERSION, "TLS_AES_128_GCM_SHA256"));
        s.track_for_offload();
        c.track_for_offload();
        pump(c, s);
        drain(c);
        EXPECT_EQ(decide(c), KtlsRefusal::AwaitingPeerRecord);
        send_via_openssl(s, c, "answer");
        EXPECT_EQ(decide(c), KtlsRefusal::None);
    }
    {
        // A TLS 1.2 suite the kernel does not take (CBC with HMAC).
        TlsSession s(context(TlsSide::Server, TLS1_2_VERSION, "ECDHE-ECDSA-AES128-SHA256"));
        TlsSession c(context(TlsSide::Client, TLS1_2_VERSION, "ECDHE-ECDSA-AES128-SHA256"));
        s.track_for_offload();
        c.track_for_offload();
        pump(c, s);
        ASSERT_TRUE(s.established()) << s.error();
        EXPECT_EQ(decide(s), KtlsRefusal::Cipher);
        KtlsParams p;
        EXPECT_FALSE(s.offload_params(p));
    }
    {
        // A session never tracked has no secrets to hand off.
        TlsSession s(context(TlsSide::Server, TLS1_3_VERSION, "TLS_AES_128_GCM_SHA256"));
        TlsSession c(context(TlsSide::Client, TLS1_3_VERSION, "TLS_AES_128_GCM_SHA256"));
        pump(c, s);
        EXPECT_EQ(decide(s), KtlsRefusal::NoSecrets);
    }
}

// What install_ktls does in ktls_hand_off's test: says what it was given, then what the test
// asks of it.
int g_installs = 0;
int g_install_result = 0;
bool g_install_changes = false;
int fake_install(int fd, const KtlsParams& params, bool& changed) {
    ++g_installs;
    EXPECT_EQ(fd, 7);
    EXPECT_NE(params.cipher, KtlsCipher::None);
    changed = g_install_changes;
    return g_install_result;
}

// ktls_hand_off, the one hand-off both the slave's and the engine's workers call: not now
// while bytes wait, never where the kernel cannot take it, done or broken as the kernel answers.
TEST_F(KtlsOffloadTest, AHandOffIsLaterUserspaceDoneOrBroken) {
    struct Installer {  // the kernel again when the test ends, however it ends
        Installer() { set_ktls_installer_for_testing(&fake_install); }
        ~Installer() { set_ktls_installer_for_testing(nullptr); }
    } installer;
    g_installs = 0;
    TlsSession s(context(TlsSide::Server, TLS1_3_VERSION, "TLS_AES_128_GCM_SHA256"));
    TlsSession c(context(TlsSide::Client, TLS1_3_VERSION, "TLS_AES_128_GCM_SHA256"));
    s.track_for_offload();
    c.track_for_offload();
    pump(c, s);
    drain(c);
    EXPECT_EQ(ktls_hand_off(c, 7, true), KtlsHandOffResult::Later);       // no answer yet
    EXPECT_EQ(ktls_hand_off(s, 7, false), KtlsHandOffResult::Userspace);  // a direct descriptor
    const Bytes request = bytes_of("request");
    ASSERT_EQ(c.write(request.data(), request.size()), TlsStatus::Ok);
    Bytes record;
    c.take_output(record);
    s.feed(record.data(), record.size());
    EXPECT_EQ(ktls_hand_off(s, 7, true), KtlsHandOffResult::Later);  // unread input
    drain(s);
    EXPECT_EQ(g_installs, 0);
    g_install_result = -ENOENT;  // no tls module: nothing changed
    g_install_changes = false;
    EXPECT_EQ(ktls_hand_off(s, 7, true), KtlsHandOffResult::Userspace);
    g_install_result = -EINVAL;  // TX installed, RX refused
    g_install_changes = true;
    EXPECT_EQ(ktls_hand_off(s, 7, true), KtlsHandOffResult::Broken);
    g_install_result = 0;
    g_install_changes = true;
    EXPECT_EQ(ktls_hand_off(s, 7, true), KtlsHandOffResult::Done);
    EXPECT_EQ(g_installs, 3);
}

// A TLS 1.3 key update before the hand-off leaves the tracked secrets stale: both ends see it
// (raw OpenSSL here: TlsSession has no call that asks for a key update).
TEST_F(KtlsOffloadTest, AKeyUpdateIsSeenByBothEnds) {
    auto server_ctx = context(TlsSide::Server, TLS1_3_VERSION, "TLS_AES_128_GCM_SHA256");
    auto client_ctx = context(TlsSide::Client, TLS1_3_VERSION, "TLS_AES_128_GCM_SHA256");
    KtlsTracker server_track;
    KtlsTracker client_track;
    SSL* s = SSL_new(server_ctx->get());
    SSL* c = SSL_new(client_ctx->get());
    ASSERT_TRUE(s != nullptr && c != nullptr);
    BIO* client_end = nullptr;
    BIO* server_end = nullptr;
    ASSERT_EQ(BIO_new_bio_pair(&client_end, 0, &server_end, 0), 1);
    SSL_set_bio(c, client_end, client_end);
    SSL_set_bio(s, server_end, server_end);
    SSL_set_connect_state(c);
    SSL_set_accept_state(s);
    server_track.attach(s);
    client_track.attach(c);
    for (int i = 0; i < 20 && !(SSL_is_init_finished(s) && SSL_is_init_finished(c)); ++i) {
        SSL_do_handshake(c);
        SSL_do_handshake(s);
    }
    ASSERT_TRUE(SSL_is_init_finished(s) && SSL_is_init_finished(c));
    char buf[16];
    EXPECT_LE(SSL_read(c, buf, sizeof buf), 0);  // the tickets; no data
    EXPECT_FALSE(client_track.key_updated());
    EXPECT_FALSE(server_track.key_updated());
    EXPECT_TRUE(client_track.have_secrets());

    ASSERT_EQ(SSL_key_update(c, SSL_KEY_UPDATE_REQUESTED), 1);
    ASSERT_EQ(SSL_write(c, "x", 1), 1);  // the KeyUpdate goes out first
    EXPECT_EQ(SSL_read(s, buf, sizeof buf), 1);
    EXPECT_TRUE(client_track.key_updated());
    EXPECT_TRUE(server_track.key_updated());
    SSL_free(c);
    SSL_free(s);
}

// Without the kernel's TLS (this machine), the hand-off fails before it touches the socket:
// the connection goes on with OpenSSL's ciphertext as before.
TEST(KtlsInstall, WithoutTheKernelsTlsTheSocketIsLeftAsItWas) {
    if (kernel_tls().available) GTEST_SKIP() << "this kernel offers TLS offload";
    UniqueFd listener(::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0));
    UniqueFd client(::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0));
    ASSERT_TRUE(listener.valid() && client.valid());
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t len = sizeof a;
    ASSERT_EQ(::bind(listener.get(), reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
    ASSERT_EQ(::listen(listener.get(), 1), 0);
    ASSERT_EQ(::getsockname(listener.get(), reinterpret_cast<sockaddr*>(&a), &len), 0);
    ASSERT_EQ(::connect(client.get(), reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
    UniqueFd accepted(::accept4(listener.get(), nullptr, nullptr, SOCK_CLOEXEC));
    ASSERT_TRUE(accepted.valid());

    KtlsParams p;
    p.version = TLS1_3_VERSION;
    p.cipher = KtlsCipher::Aes128Gcm;
    p.tx.key_size = p.rx.key_size = 16;
    bool changed = true;
    EXPECT_LT(install_ktls(client.get(), p, changed), 0);
    EXPECT_FALSE(changed);
    const char bytes[] = "ciphertext as before";
    ASSERT_EQ(::send(client.get(), bytes, sizeof bytes, 0), static_cast<ssize_t>(sizeof bytes));
    char got[sizeof bytes] = {};
    ASSERT_EQ(::recv(accepted.get(), got, sizeof got, MSG_WAITALL),
              static_cast<ssize_t>(sizeof got));
    EXPECT_STREQ(got, bytes);
}

}  // namespace
}  // namespace mbstorm::net
