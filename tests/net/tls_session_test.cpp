// TlsContext and TlsSession over memory BIOs: two sessions in one process, the ciphertext
// moved by hand, with certificates made by openssl(1) (tests/scripts/lib/tls_certs.bash).
#include <gtest/gtest.h>
#include <openssl/ssl.h>

#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "net/tls_context.hpp"
#include "net/tls_session.hpp"

namespace mbstorm::net {
namespace {

class TlsSessionTest : public ::testing::Test {
  protected:
    static void SetUpTestSuite() {
        dir_ = new std::string(std::filesystem::temp_directory_path() /
                               ("mbstorm-tls-test-" + std::to_string(::getpid())));
        std::filesystem::create_directories(*dir_);
        const std::string cmd = std::string("bash -c 'source ") + MBSTORM_SOURCE_DIR +
                                "/tests/scripts/lib/tls_certs.bash && make_tls_certs " + *dir_ +
                                "'";
        made_ = std::system(cmd.c_str()) == 0;
    }
    static void TearDownTestSuite() {
        std::filesystem::remove_all(*dir_);
        delete dir_;
    }
    void SetUp() override {
        if (!made_) GTEST_SKIP() << "openssl could not make the test certificates";
    }

    static std::string file(const std::string& name) { return *dir_ + "/" + name; }
    static std::shared_ptr<TlsContext> server() {
        std::string error;
        auto ctx = TlsContext::create(
            TlsSide::Server, {file("server.pem"), file("server.key"), file("ca.pem")}, error);
        EXPECT_TRUE(ctx) << error;
        return ctx;
    }
    static std::shared_ptr<TlsContext> client(const std::string& who, int max_version = 0) {
        std::string error;
        auto ctx = TlsContext::create(
            TlsSide::Client, {file(who + ".pem"), file(who + ".key"), file("ca.pem")}, error);
        EXPECT_TRUE(ctx) << error;
        if (ctx && max_version != 0) SSL_CTX_set_max_proto_version(ctx->get(), max_version);
        return ctx;
    }

    // Moves ciphertext both ways until neither side has any left (bounded).
    static void pump(TlsSession& a, TlsSession& b) {
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
    // Reads what `s` has decrypted (processing tickets on the way).
    static std::string drain(TlsSession& s) {
        std::uint8_t out[256];
        std::size_t n = 0;
        std::string text;
        while (s.read(out, sizeof out, n) == TlsStatus::Ok && n > 0)
            text.append(reinterpret_cast<const char*>(out), n);
        return text;
    }

    static std::string* dir_;
    static bool made_;
};

std::string* TlsSessionTest::dir_ = nullptr;
bool TlsSessionTest::made_ = false;

TEST_F(TlsSessionTest, MutualHandshakeCarriesDataAndTheClientsRole) {
    for (const int version : {TLS1_3_VERSION, TLS1_2_VERSION}) {
        TlsSession s(server());
        TlsSession c(client("operator", version));
        pump(c, s);
        ASSERT_TRUE(c.established()) << c.error();
        ASSERT_TRUE(s.established()) << s.error();
        EXPECT_EQ(s.peer_role(), "Operator");
        EXPECT_STREQ(c.version(), version == TLS1_3_VERSION ? "TLSv1.3" : "TLSv1.2");
        const std::string request = "\x00\x01\x00\x00\x00\x06\x01\x03\x00\x00\x00\x02";
        ASSERT_EQ(c.write(reinterpret_cast<const std::uint8_t*>(request.data()), request.size()),
                  TlsStatus::Ok);
        pump(c, s);
        EXPECT_EQ(drain(s), request);
    }
}

TEST_F(TlsSessionTest, ServerRefusesAClientWithoutARoleOrOfAnotherCa) {
    for (const char* who : {"norole", "rogue"}) {
        TlsSession s(server());
        TlsSession c(client(who));
        pump(c, s);
        drain(c);  // TLS 1.3: the client learns of the refusal after its own handshake
        EXPECT_FALSE(s.established()) << who;
        EXPECT_FALSE(s.error().empty()) << who;
    }
}

TEST_F(TlsSessionTest, ASavedSessionIsResumed) {
    auto server_ctx = server();
    auto client_ctx = client("operator");
    SSL_SESSION* saved = nullptr;
    {
        TlsSession s(server_ctx);
        TlsSession c(client_ctx);
        pump(c, s);
        drain(c);  // the TLS 1.3 tickets
        EXPECT_FALSE(c.resumed());
        saved = c.saved_session();
        ASSERT_NE(saved, nullptr);
    }  // both freed as a connection that simply ended: the session must stay resumable
    TlsSession s(server_ctx);
    TlsSession c(client_ctx, saved);
    pump(c, s);
    free_tls_session(saved);
    ASSERT_TRUE(c.established()) << c.error();
    EXPECT_TRUE(c.resumed());
    EXPECT_TRUE(s.resumed());
    EXPECT_EQ(s.peer_role(), "Operator");  // the resumed session keeps the certificate
}

TEST_F(TlsSessionTest, MissingFilesAreNamed) {
    std::string error;
    EXPECT_FALSE(TlsContext::create(TlsSide::Server,
                                    {file("nope.pem"), file("server.key"), file("ca.pem")}, error));
    EXPECT_NE(error.find("nope.pem"), std::string::npos) << error;
    error.clear();
    EXPECT_FALSE(TlsContext::create(TlsSide::Client, {"", "", ""}, error));
    EXPECT_NE(error.find("--tls-cert"), std::string::npos) << error;
    error.clear();
    EXPECT_FALSE(TlsContext::create(
        TlsSide::Server, {file("server.pem"), file("operator.key"), file("ca.pem")}, error));
    EXPECT_NE(error.find("operator.key with certificate"), std::string::npos) << error;
}

}  // namespace
}  // namespace mbstorm::net
