// The fuzzer's TLS link (netfuzz/tls_link) against `mbstorm serve --transport tls`, with
// certificates made by openssl(1) (tests/scripts/lib/tls_certs.bash): MBAP through the
// session, decrypted bytes poll() cannot see, resumption, refusals, a silent peer, close_notify
// as the half-close, and the plain TCP connection beside the session; and the cases that speak
// the other transport to the port (netfuzz/cross_transport).
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "fuzz_test_support.hpp"
#include "net/clock.hpp"
#include "netfuzz/campaign.hpp"
#include "netfuzz/cross_transport.hpp"
#include "netfuzz/executor.hpp"
#include "netfuzz/finding.hpp"
#include "netfuzz/tls_link.hpp"

namespace mbstorm::netfuzz {
namespace {

class TlsLinkTest : public ::testing::Test {
  protected:
    static void SetUpTestSuite() {
        dir_ = new std::string(test::temp_dir("tls-link"));
        const std::string cmd = std::string("bash -c 'source ") + MBSTORM_SOURCE_DIR +
                                "/tests/scripts/lib/tls_certs.bash && make_tls_certs " + *dir_ +
                                "'";
        if (std::system(cmd.c_str()) != 0) return;
        server_ = new std::unique_ptr<test::Target>();
        const std::string at = test::start_reference_slave(
            *server_, {"--transport", "tls", "--tls-cert", file("server.pem"), "--tls-key",
                       file("server.key"), "--tls-ca", file("ca.pem")});
        if (!at.empty()) target_ = new std::string(at);
    }
    static void TearDownTestSuite() {
        delete server_;
        std::filesystem::remove_all(*dir_);
        delete dir_;
        delete target_;
    }
    void SetUp() override {
        if (target_ == nullptr) GTEST_SKIP() << "no certificates (openssl) or no TLS server";
    }

    static std::string file(const std::string& name) { return *dir_ + "/" + name; }
    static net::Endpoint endpoint() {
        Result<net::Endpoint> e = net::parse_endpoint(*target_, 802);
        EXPECT_TRUE(e.ok()) << e.error().text();
        return e.ok() ? *e : net::Endpoint{};
    }
    // `who`'s client context trusting the CA (nullptr, the test failed, when it cannot be made).
    static std::shared_ptr<net::TlsContext> client_context(const std::string& who) {
        Result<std::shared_ptr<net::TlsContext>> ctx = net::TlsContext::create(
            net::TlsSide::Client, {file(who + ".pem"), file(who + ".key"), file("ca.pem")});
        EXPECT_TRUE(ctx.ok()) << ctx.error().text();
        return ctx.ok() ? std::move(ctx).value() : nullptr;
    }
    static std::shared_ptr<TlsConnector> connector(const std::string& who, bool resume = false) {
        auto ctx = client_context(who);
        return std::make_shared<TlsConnector>(endpoint(), ctx, resume);
    }
    // Reads until `want` bytes came, the stream ended or 3 s passed; `chunk` bytes per recv.
    static std::vector<std::uint8_t> read_bytes(Link& link, std::size_t want, ssize_t& last,
                                                std::size_t chunk = 4096) {
        std::vector<std::uint8_t> got;
        std::vector<std::uint8_t> buf(chunk);
        const std::int64_t deadline = net::now_ns() + 3 * net::kNsPerSec;
        last = -EAGAIN;
        while (got.size() < want && net::now_ns() < deadline) {
            if (!wait_readable(link, 100)) continue;
            last = link.recv(buf.data(), buf.size());
            if (last > 0)
                got.insert(got.end(), buf.begin(), buf.begin() + last);
            else if (last != -EAGAIN)
                break;
        }
        return got;
    }
    static std::vector<std::uint8_t> read_request(std::uint16_t tid) {
        return frame_pdu({0x03, 0x00, 0x00, 0x00, 0x01}, tid, 1);  // answer: 11 bytes
    }

    static std::string* dir_;
    static std::unique_ptr<test::Target>* server_;
    static std::string* target_;
};

std::string* TlsLinkTest::dir_ = nullptr;
std::unique_ptr<test::Target>* TlsLinkTest::server_ = nullptr;
std::string* TlsLinkTest::target_ = nullptr;

TEST_F(TlsLinkTest, CarriesMbapThroughTheSessionAndKeepsDecryptedBytesVisible) {
    auto c = connector("operator");
    int error = 0;
    std::unique_ptr<Link> link = c->open(2000, error);
    ASSERT_TRUE(link) << std::strerror(error) << c->last_failure();
    EXPECT_EQ(c->describe(), *target_ + " (TLS)");
    // Two requests in one send: both answers arrive decrypted together.
    std::vector<std::uint8_t> two = read_request(0x0101);
    const auto second = read_request(0x0202);
    two.insert(two.end(), second.begin(), second.end());
    ASSERT_EQ(link->send(two.data(), two.size()), static_cast<ssize_t>(two.size()));
    ASSERT_TRUE(wait_readable(*link, 3000));
    // Read one byte at a time: what the session decrypted and recv() has not returned yet is
    // reported as buffered, since poll() on the socket cannot see it.
    ssize_t last = 0;
    const auto answers = read_bytes(*link, 22, last, 1);
    ASSERT_EQ(answers.size(), 22u) << last;
    EXPECT_EQ(answers[0], 0x01);
    EXPECT_EQ(answers[1], 0x01);
    EXPECT_EQ(answers[11], 0x02);
    EXPECT_EQ(answers[12], 0x02);
    EXPECT_FALSE(link->has_buffered_input());
    EXPECT_EQ(link->recv(nullptr, 0), -EAGAIN);
}

TEST_F(TlsLinkTest, BufferedInputIsReportedWhilePartlyRead) {
    auto c = connector("operator");
    int error = 0;
    std::unique_ptr<Link> link = c->open(2000, error);
    ASSERT_TRUE(link);
    const auto rq = read_request(7);
    ASSERT_EQ(link->send(rq.data(), rq.size()), static_cast<ssize_t>(rq.size()));
    ASSERT_TRUE(wait_readable(*link, 3000));
    std::uint8_t first[4];
    ssize_t n = -EAGAIN;
    for (int i = 0; i < 300 && n == -EAGAIN; ++i) {
        wait_readable(*link, 10);
        n = link->recv(first, sizeof first);
    }
    ASSERT_EQ(n, 4);
    EXPECT_TRUE(link->has_buffered_input());
    EXPECT_TRUE(wait_readable(*link, 0));  // at once: no wait on the socket
    ssize_t last = 0;
    EXPECT_EQ(read_bytes(*link, 7, last).size(), 7u);
}

TEST_F(TlsLinkTest, ResumesSessionsOnlyWhenAsked) {
    for (const bool resume : {true, false}) {
        auto c = connector("operator", resume);
        for (int i = 0; i < 3; ++i) {
            int error = 0;
            std::unique_ptr<Link> link = c->open(2000, error);
            ASSERT_TRUE(link) << c->last_failure();
            // An answer read means the TLS 1.3 ticket before it was read too.
            const auto rq = read_request(static_cast<std::uint16_t>(i));
            ASSERT_GT(link->send(rq.data(), rq.size()), 0);
            ssize_t last = 0;
            ASSERT_EQ(read_bytes(*link, 11, last).size(), 11u);
        }
        EXPECT_EQ(c->shared().handshakes.load(), 3u);
        if (resume)
            EXPECT_EQ(c->shared().resumed.load(), 2u);
        else
            EXPECT_EQ(c->shared().resumed.load(), 0u);
    }
}

TEST_F(TlsLinkTest, RefusedCertificateIsAFailedOpenOrABrokenSessionWithTheReason) {
    auto c = connector("rogue");  // signed by another CA
    int error = 0;
    std::unique_ptr<Link> link = c->open(2000, error);
    if (link) {
        // TLS 1.3: the client's handshake ends before the server has judged its certificate;
        // the refusal is the alert that follows.
        const auto rq = read_request(1);
        link->send(rq.data(), rq.size());
        ssize_t last = 0;
        EXPECT_TRUE(read_bytes(*link, 11, last).empty());
        EXPECT_EQ(last, -EPROTO);
    } else {
        EXPECT_EQ(error, EPROTO);
    }
    EXPECT_NE(c->last_failure(), "");
    EXPECT_EQ(c->shared().handshake_failures.load(), 1u);
}

TEST_F(TlsLinkTest, SilentPeerFailsTheHandshakeAtTheTimeout) {
    const int listener = ::socket(AF_INET, SOCK_STREAM, 0);
    ASSERT_GE(listener, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ASSERT_EQ(::bind(listener, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
    ASSERT_EQ(::listen(listener, 4), 0);
    socklen_t len = sizeof a;
    ::getsockname(listener, reinterpret_cast<sockaddr*>(&a), &len);
    const net::Endpoint silent =
        *net::parse_endpoint("127.0.0.1:" + std::to_string(ntohs(a.sin_port)), 802);
    auto ctx = client_context("operator");
    TlsConnector c(silent, ctx, false);
    const auto t0 = std::chrono::steady_clock::now();
    int code = 0;
    EXPECT_FALSE(c.open(300, code));
    EXPECT_EQ(code, ETIMEDOUT);
    EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(3));
    EXPECT_NE(c.last_failure().find("no TLS handshake"), std::string::npos) << c.last_failure();
    ::close(listener);
}

TEST_F(TlsLinkTest, HalfCloseIsCloseNotifyAndCompleteRequestsAreStillAnswered) {
    auto c = connector("operator");
    int error = 0;
    std::unique_ptr<Link> link = c->open(2000, error);
    ASSERT_TRUE(link);
    const auto rq = read_request(9);
    ASSERT_GT(link->send(rq.data(), rq.size()), 0);
    link->shutdown_write();
    ssize_t last = 0;
    EXPECT_EQ(read_bytes(*link, 11, last).size(), 11u);
    read_bytes(*link, 1, last);
    EXPECT_EQ(last, 0);  // then the server ends the session
}

TEST_F(TlsLinkTest, PlaintextBesideOrInsteadOfTheSessionIsRefused) {
    auto c = connector("operator");
    int error = 0;
    // Plain Modbus/TCP to the TLS port: at most a TLS alert record (type 21), then the
    // connection closes.
    std::unique_ptr<Link> plain = c->open_plain(2000, error);
    ASSERT_TRUE(plain);
    const auto rq = read_request(3);
    ASSERT_EQ(plain->send(rq.data(), rq.size()), static_cast<ssize_t>(rq.size()));
    ssize_t last = 0;
    const auto reply = read_bytes(*plain, 64, last);
    if (!reply.empty()) {
        EXPECT_EQ(reply[0], 21);
    }
    EXPECT_TRUE(last == 0 || last == -ECONNRESET) << last;
    // Plaintext between the records of an established session: the server drops it.
    std::unique_ptr<Link> link = c->open(2000, error);
    ASSERT_TRUE(link);
    auto* tls = dynamic_cast<TlsLink*>(link.get());
    ASSERT_NE(tls, nullptr);
    EXPECT_EQ(tls->send_beside_session(rq.data(), rq.size(), 1000),
              static_cast<ssize_t>(rq.size()));
    EXPECT_TRUE(read_bytes(*link, 1, last).empty());
    EXPECT_TRUE(last == 0 || last == -EPROTO || last == -ECONNRESET) << last;
    // And the server goes on serving others.
    link = c->open(2000, error);
    ASSERT_TRUE(link);
    ASSERT_GT(link->send(rq.data(), rq.size()), 0);
    EXPECT_EQ(read_bytes(*link, 11, last).size(), 11u);
}

TEST_F(TlsLinkTest, DiscoveryAndACaseRunOverTheSession) {
    auto c = connector("operator");
    TargetProfile profile;
    const Error error = discover_target(*c, 1, 2000, profile);
    ASSERT_TRUE(error.ok()) << error.text() << c->last_failure();
    EXPECT_FALSE(profile.probe_pdu.empty());
    Case one;
    one.cls = MutationClass::ValidLimits;
    one.function = 0x03;
    one.steps.push_back(Step{Op::Send, 0, 0, 0, read_request(0x0042)});
    const Execution e = execute_case(one, *c, profile, ExecOptions{});
    EXPECT_FALSE(e.verdict) << e.verdict.summary;
}

TEST_F(TlsLinkTest, PlaintextCasesFindNothingOnAServerThatRefusesThem) {
    auto c = connector("operator");
    TargetProfile profile;
    const Error error = discover_target(*c, 1, 2000, profile);
    ASSERT_TRUE(error.ok()) << error.text();
    const std::vector<Case> cases = cross_transport_cases(*c, profile);
    ASSERT_EQ(cases.size(), 7u);
    for (const Case& k : cases) {
        ASSERT_TRUE(k.cls == MutationClass::PlaintextToTls ||
                    k.cls == MutationClass::PlaintextInSession);
        const Execution e = execute_case(k, *c, profile, ExecOptions{});
        EXPECT_FALSE(e.verdict) << class_name(k.cls) << ": " << e.verdict.summary;
        EXPECT_FALSE(e.down_before);
        // The server refused the connection: it ended, no Modbus answer came.
        bool ended = false;
        for (const TraceEvent& t : e.trace)
            ended = ended || (t.conn == 0 &&
                              (t.kind == TraceKind::PeerClosed || t.kind == TraceKind::Reset));
        EXPECT_TRUE(ended) << class_name(k.cls);
    }
}

TEST_F(TlsLinkTest, TlsCasesFindNothingOnAPlainServer) {
    std::unique_ptr<test::Target> plain_server;
    const std::string at = test::start_reference_slave(plain_server);
    ASSERT_FALSE(at.empty());
    net::Endpoint e = *net::parse_endpoint(at, 502);
    std::string error;
    TcpConnector plain(e);
    TargetProfile profile;
    const Error discovered = discover_target(plain, 1, 2000, profile);
    ASSERT_TRUE(discovered.ok()) << discovered.text();
    const std::vector<Case> cases = cross_transport_cases(plain, profile);
    ASSERT_EQ(cases.size(), 4u);
    for (const Case& k : cases) {
        EXPECT_EQ(k.cls, MutationClass::TlsToPlain);
        ASSERT_FALSE(k.steps.empty());
        EXPECT_EQ(k.steps[0].bytes[0], 0x16);  // a TLS handshake record
        const Execution x = execute_case(k, plain, profile, ExecOptions{});
        EXPECT_FALSE(x.verdict) << x.verdict.summary;
    }
}

// A TLS port that also serves plain Modbus/TCP (tests/scripts/tls_plaintext_too_server.py):
// the plaintext case is answered, which is the finding, and the saved finding replays to the
// same fault.
TEST_F(TlsLinkTest, ATlsPortThatAnswersPlaintextIsAFindingThatReplays) {
    if (::access("/usr/bin/python3", X_OK) != 0) GTEST_SKIP() << "no /usr/bin/python3";
    test::Target broken(
        {"/usr/bin/python3",
         std::string(MBSTORM_SOURCE_DIR) + "/tests/scripts/tls_plaintext_too_server.py", *dir_});
    const std::string line = broken.wait_for_line("PORT ");
    ASSERT_FALSE(line.empty());
    net::Endpoint e = *net::parse_endpoint("127.0.0.1:" + line.substr(5), 802);
    std::string error;
    auto ctx = client_context("operator");
    ASSERT_TRUE(ctx);
    TlsConnector posing(e, ctx, false);
    TargetProfile profile;
    profile.probe_pdu = {0x03, 0x00, 0x00, 0x00, 0x01};
    const std::vector<Case> cases = cross_transport_cases(posing, profile);
    ASSERT_FALSE(cases.empty());
    const Case& plaintext = cases.front();
    ASSERT_EQ(plaintext.cls, MutationClass::PlaintextToTls);
    const Execution x = execute_case(plaintext, posing, profile, ExecOptions{});
    EXPECT_EQ(x.verdict.oracle, Oracle::SpecDeviation) << x.verdict.summary;
    EXPECT_EQ(x.verdict.rule, "tls-port-answers-plaintext");
    Finding f;
    f.id = 1;
    f.verdict = x.verdict;
    f.fuzz_case = f.original_case = plaintext;
    f.profile = profile;
    f.trace = x.trace;
    const std::string dir = *dir_ + "/finding";
    ASSERT_TRUE(save_finding(f, dir).ok());
    const Result<Finding> read = load_finding(dir);
    ASSERT_TRUE(read.ok()) << read.error().text();
    const Finding& loaded = *read;
    EXPECT_EQ(loaded.fuzz_case.cls, MutationClass::PlaintextToTls);
    const Execution again = execute_case(loaded.fuzz_case, posing, loaded.profile, ExecOptions{});
    EXPECT_TRUE(same_fault(again.verdict, f.verdict)) << again.verdict.summary;
}

}  // namespace
}  // namespace mbstorm::netfuzz
