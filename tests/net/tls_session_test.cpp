// TlsContext and TlsSession over memory BIOs: two sessions in one process, the ciphertext
// moved by hand, with certificates made by openssl(1) (tests/scripts/lib/tls_certs.bash).
#include <gtest/gtest.h>
#include <openssl/ssl.h>

#include <memory>
#include <string>

#include "../support/tls_test_support.hpp"
#include "net/tls_context.hpp"
#include "net/tls_session.hpp"

namespace mbstorm::net {
namespace {

using test::drain_text;
using test::pump;

class TlsSessionTest : public test::TlsCertsTest {
  protected:
    static std::shared_ptr<TlsContext> server() { return context(TlsSide::Server, "server"); }
    static std::shared_ptr<TlsContext> client(const std::string& who, int max_version = 0) {
        return context(TlsSide::Client, who, max_version);
    }
};

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
        EXPECT_EQ(drain_text(s), request);
    }
}

TEST_F(TlsSessionTest, ServerRefusesAClientWithoutARoleOrOfAnotherCa) {
    // "trailing": a role extension with bytes after its UTF8String is no role.
    for (const char* who : {"norole", "trailing", "rogue"}) {
        TlsSession s(server());
        TlsSession c(client(who));
        pump(c, s);
        drain_text(c);  // TLS 1.3: the client learns of the refusal after its own handshake
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
        drain_text(c);  // the TLS 1.3 tickets
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
    auto refusal = [](const TlsFiles& files) {
        const Result<std::shared_ptr<TlsContext>> context =
            TlsContext::create(TlsSide::Server, files);
        EXPECT_EQ(context.error().code(), ErrorCode::InvalidInput);
        return context.error().text();
    };
    std::string error = refusal({file("nope.pem"), file("server.key"), file("ca.pem")});
    EXPECT_NE(error.find("nope.pem"), std::string::npos) << error;
    error = refusal({"", "", ""});
    EXPECT_NE(error.find("--tls-cert"), std::string::npos) << error;
    error = refusal({file("server.pem"), file("operator.key"), file("ca.pem")});
    EXPECT_NE(error.find("operator.key with certificate"), std::string::npos) << error;
}

}  // namespace
}  // namespace mbstorm::net
