// The kernel TLS hand-off's hooks in a real run, on a kernel without the offload: the probe
// is told to say "available" and install_ktls is replaced by a fake that records what each
// side would hand to the kernel and then refuses (as a kernel without the tls module does,
// before it changes anything). Every connection, on both sides, must reach a hand-off point
// with parameters that agree with its peer's, then go on in userspace unharmed.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <openssl/ssl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "../support/tls_test_support.hpp"
#include "load/engine.hpp"
#include "net/kernel_tls.hpp"
#include "net/ktls_offload.hpp"
#include "net/tls_context.hpp"
#include "server/server.hpp"

namespace mbstorm::load {
namespace {

using namespace std::chrono_literals;

struct HandOff {
    std::uint16_t local_port;
    net::KtlsParams params;
};

std::mutex seen_mutex;
std::map<std::uint16_t, std::vector<HandOff>> seen;  // by the client's port

std::uint16_t port_of(int fd, bool peer) {
    sockaddr_in a{};
    socklen_t len = sizeof a;
    const int rc = peer ? ::getpeername(fd, reinterpret_cast<sockaddr*>(&a), &len)
                        : ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
    return rc == 0 ? ntohs(a.sin_port) : 0;
}

std::uint16_t server_port = 0;

int refuse_after_recording(int fd, const net::KtlsParams& params, bool& changed) {
    changed = false;
    const std::uint16_t local = port_of(fd, false);
    const std::uint16_t client = local == server_port ? port_of(fd, true) : local;
    std::lock_guard<std::mutex> lock(seen_mutex);
    seen[client].push_back({local, params});
    return -ENOENT;  // what TCP_ULP "tls" says without the module
}

class TlsOffloadEngine : public test::TlsCertsTest {
  protected:
    void SetUp() override {
        TlsCertsTest::SetUp();
        if (IsSkipped()) return;
        if (net::kernel_tls().available) GTEST_SKIP() << "this kernel has the offload itself";
        net::pretend_kernel_tls_for_testing(true);
        net::set_ktls_installer_for_testing(&refuse_after_recording);
        std::lock_guard<std::mutex> lock(seen_mutex);
        seen.clear();
    }
    void TearDown() override {
        net::set_ktls_installer_for_testing(nullptr);
        net::pretend_kernel_tls_for_testing(false);
    }
};

TEST_F(TlsOffloadEngine, EveryConnectionReachesAHandOffThatAgreesWithItsPeer) {
    for (const int version : {TLS1_3_VERSION, TLS1_2_VERSION}) {
        SCOPED_TRACE(version == TLS1_3_VERSION ? "TLS 1.3" : "TLS 1.2");
        {
            std::lock_guard<std::mutex> lock(seen_mutex);
            seen.clear();
        }
        server::ServerConfig config;
        config.listen = "127.0.0.1:0";
        config.threads = 1;
        config.tls = context(net::TlsSide::Server, "server");
        ASSERT_TRUE(config.tls);
        server::Server srv(config);
        const Error error = srv.start();
        ASSERT_TRUE(error.ok()) << error.text();
        server_port = srv.port();

        Plan plan;
        plan.host = "127.0.0.1";
        plan.port = srv.port();
        plan.tls = context(net::TlsSide::Client, "operator", version);
        ASSERT_TRUE(plan.tls);
        Operation op;
        op.name = "read";
        op.function = 0x03;
        op.first_address = 0;
        op.last_address = 99;
        op.quantity = 4;
        plan.operations = {op};
        plan.threads = 1;
        plan.connections = 4;
        plan.depth = 4;  // sends and answers overlap: the hand-off must still find its moment
        plan.transactions = 2000;
        plan.duration = 20s;  // ended by the transaction count long before
        const LoadResult r = run_load(plan);
        ASSERT_TRUE(r.ok()) << r.error;
        EXPECT_EQ(r.run.counters.ok(), 2000u);
        EXPECT_EQ(r.run.connections.tls_handshakes, 4u);
        // The fake refused every hand-off: nothing was offloaded, nothing broke.
        EXPECT_EQ(r.run.connections.tls_offloaded, 0u);
        EXPECT_EQ(r.run.connections.tls_offload_errors, 0u);
        const server::ServerStats s = srv.stats();
        EXPECT_EQ(s.tls_offloaded, 0u);
        EXPECT_EQ(s.tls_offload_errors, 0u);

        std::lock_guard<std::mutex> lock(seen_mutex);
        ASSERT_EQ(seen.size(), 4u) << "a connection never reached its hand-off";
        for (const auto& [client_port, handoffs] : seen) {
            // Once per side: a refused hand-off is not tried again.
            ASSERT_EQ(handoffs.size(), 2u) << "client port " << client_port;
            const bool first_is_server = handoffs[0].local_port == server_port;
            const net::KtlsParams& sp = handoffs[first_is_server ? 0 : 1].params;
            const net::KtlsParams& cp = handoffs[first_is_server ? 1 : 0].params;
            EXPECT_EQ(sp.version, version);
            EXPECT_EQ(cp.version, version);
            EXPECT_NE(sp.cipher, net::KtlsCipher::None);
            EXPECT_EQ(sp.cipher, cp.cipher);
            // The keys and static IVs agree (the sequence numbers are each side's own moment;
            // TLS 1.2 AES-GCM's explicit nonce half follows them).
            const std::size_t fixed =
                version == TLS1_2_VERSION && sp.cipher != net::KtlsCipher::Chacha20Poly1305 ? 4
                                                                                            : 12;
            EXPECT_EQ(sp.tx.key, cp.rx.key);
            EXPECT_EQ(sp.rx.key, cp.tx.key);
            EXPECT_TRUE(std::equal(sp.tx.iv.begin(), sp.tx.iv.begin() + fixed, cp.rx.iv.begin()));
            EXPECT_TRUE(std::equal(sp.rx.iv.begin(), sp.rx.iv.begin() + fixed, cp.tx.iv.begin()));
            EXPECT_NE(sp.tx.key, sp.rx.key);
            if (version == TLS1_3_VERSION) {
                // The server's tickets went out under its application keys before anything.
                EXPECT_GE(sp.tx.seq, 1u);
                EXPECT_GE(cp.rx.seq, 1u) << "the client handed off before an answer";
            }
        }
        srv.stop();
    }
}

}  // namespace
}  // namespace mbstorm::load
