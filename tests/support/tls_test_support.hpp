// What the TLS suites share: certificates made once per suite by openssl(1)
// (tests/scripts/lib/tls_certs.bash: a CA, "server", the clients "operator", "viewer",
// "norole", "trailing" (bytes after its role) and "rogue" of another CA), contexts built from
// them, and an OpenSSL client and server in one process with the ciphertext moved between them
// by hand (memory BIOs).
#pragma once

#include <gtest/gtest.h>
#include <openssl/ssl.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "net/tls_context.hpp"
#include "net/tls_session.hpp"

namespace mbstorm::test {

// A suite's certificates: made in SetUpTestSuite, removed in TearDownTestSuite; every test
// is skipped when openssl(1) could not make them.
class TlsCertsTest : public ::testing::Test {
  protected:
    static void SetUpTestSuite() {
        dir_ = std::filesystem::temp_directory_path() /
               ("mbstorm-tls-test-" + std::to_string(::getpid()) + "-" + std::to_string(++suites_));
        std::filesystem::create_directories(dir_);
        const std::string cmd = std::string("bash -c 'source ") + MBSTORM_SOURCE_DIR +
                                "/tests/scripts/lib/tls_certs.bash && make_tls_certs " + dir_ + "'";
        made_ = std::system(cmd.c_str()) == 0;
    }
    static void TearDownTestSuite() {
        std::filesystem::remove_all(dir_);
        dir_.clear();
        made_ = false;
    }
    void SetUp() override {
        if (!made_) GTEST_SKIP() << "openssl could not make the test certificates";
    }

    static std::string file(const std::string& name) { return dir_ + "/" + name; }
    // `who`'s certificate and key ("server", "operator", ...) trusting the CA; max_version
    // (TLS1_2_VERSION, ...) caps the protocol, 0 leaves OpenSSL's range.
    static std::shared_ptr<net::TlsContext> context(net::TlsSide side, const std::string& who,
                                                    int max_version = 0) {
        Result<std::shared_ptr<net::TlsContext>> made =
            net::TlsContext::create(side, {file(who + ".pem"), file(who + ".key"), file("ca.pem")});
        EXPECT_TRUE(made.ok()) << made.error().text();
        if (!made.ok()) return nullptr;
        std::shared_ptr<net::TlsContext> ctx = std::move(made).value();
        if (max_version != 0) SSL_CTX_set_max_proto_version(ctx->get(), max_version);
        return ctx;
    }

  private:
    static inline std::string dir_;
    static inline bool made_ = false;
    static inline int suites_ = 0;  // suites of this process so far: one directory each
};

// Moves ciphertext both ways until neither side has any left, handshaking on the way
// (bounded: ten round trips).
inline void pump(net::TlsSession& a, net::TlsSession& b) {
    std::vector<std::uint8_t> buf;
    for (int i = 0; i < 10; ++i) {
        if (!a.established()) a.handshake();
        if (!b.established()) b.handshake();
        buf.clear();
        a.take_output(buf);
        b.feed(buf.data(), buf.size());
        const bool a_sent = !buf.empty();
        if (!b.established()) b.handshake();
        buf.clear();
        b.take_output(buf);
        a.feed(buf.data(), buf.size());
        if (!a_sent && buf.empty()) return;
    }
}

// All that `s` has decrypted (processing tickets and key updates on the way).
inline std::vector<std::uint8_t> drain(net::TlsSession& s) {
    std::uint8_t out[512];
    std::size_t n = 0;
    std::vector<std::uint8_t> plain;
    while (s.read(out, sizeof out, n) == net::TlsStatus::Ok && n > 0)
        plain.insert(plain.end(), out, out + n);
    return plain;
}

inline std::string drain_text(net::TlsSession& s) {
    const std::vector<std::uint8_t> plain = drain(s);
    return std::string(plain.begin(), plain.end());
}

}  // namespace mbstorm::test
