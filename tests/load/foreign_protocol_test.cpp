// A target that speaks another protocol (an HTTP server, TLS, SSH): every transaction is a
// framing error, and the run says what the answers looked like instead of only "received 0 B"
// (issue #29, silent wrong answers, item 2).
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <string>
#include <thread>

#include "../support/loopback_listener.hpp"
#include "load/engine.hpp"
#include "load/foreign_protocol.hpp"

namespace mbstorm::load {
namespace {

using namespace std::chrono_literals;

codec::Bytes bytes_of(const char* text) {
    return codec::Bytes(reinterpret_cast<const std::uint8_t*>(text), std::strlen(text));
}

TEST(ForeignProtocol, NamesWhatTheAnswersLookLike) {
    EXPECT_EQ(describe_foreign_bytes(bytes_of("HTTP/1.0 400 Bad")),
              "an HTTP server (\"HTTP/1.0 400 Bad\")");
    EXPECT_EQ(describe_foreign_bytes(bytes_of("<!DOCTYPE HTML>\n")),
              "an HTTP server (\"<!DOCTYPE HTML> \")");
    EXPECT_EQ(describe_foreign_bytes(bytes_of("SSH-2.0-OpenSSH")),
              "an SSH server (\"SSH-2.0-OpenSSH\")");
    const std::uint8_t alert[] = {0x15, 0x03, 0x03, 0x00, 0x02, 0x02, 0x28};
    EXPECT_EQ(describe_foreign_bytes(codec::Bytes(alert, sizeof alert)),
              "a TLS server: try --transport tls (15 03 03 00 02 02 28)");
    EXPECT_EQ(describe_foreign_bytes(bytes_of("220 ftp ready\r\n")),
              "a text protocol (\"220 ftp ready  \")");
    const std::uint8_t junk[] = {0x00, 0xFF, 0x10};
    EXPECT_EQ(describe_foreign_bytes(codec::Bytes(junk, sizeof junk)), "not Modbus/TCP (00 FF 10)");
    EXPECT_EQ(describe_foreign_bytes({}), "");
}

// Answers whatever it receives with an HTTP error and closes, as `python3 -m http.server`
// does to a Modbus request.
class HttpLikeServer {
  public:
    HttpLikeServer() {
        listen_fd_ = test::listen_on_loopback(64, port_);
        EXPECT_GE(listen_fd_, 0);
        thread_ = std::thread([this] { serve(); });
    }
    ~HttpLikeServer() {
        stop_ = true;
        thread_.join();
        ::close(listen_fd_);
    }
    std::uint16_t port() const { return port_; }

  private:
    void serve() {
        static const char kAnswer[] = "HTTP/1.0 400 Bad request\r\nServer: test\r\n\r\n";
        while (!stop_) {
            pollfd p{listen_fd_, POLLIN, 0};
            if (::poll(&p, 1, 20) <= 0) continue;
            const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
            if (fd < 0) continue;
            pollfd q{fd, POLLIN, 0};
            std::uint8_t in[512];
            if (::poll(&q, 1, 500) > 0 && ::recv(fd, in, sizeof in, 0) > 0)
                (void)::send(fd, kAnswer, sizeof kAnswer - 1, MSG_NOSIGNAL);
            ::close(fd);
        }
    }
    int listen_fd_ = -1;
    std::uint16_t port_ = 0;
    std::atomic<bool> stop_{false};
    std::thread thread_;
};

TEST(ForeignProtocol, ARunAgainstAnHttpServerSaysItLooksLikeOne) {
    HttpLikeServer server;
    Plan plan;
    plan.host = "127.0.0.1";
    plan.port = server.port();
    Operation op;
    op.name = "read";
    op.function = 0x03;
    op.first_address = 0;
    op.last_address = 9;
    op.quantity = 1;
    plan.operations = {op};
    plan.threads = 1;
    plan.connections = 1;
    plan.depth = 1;
    plan.duration = 0s;
    plan.transactions = 20;
    const LoadResult r = run_load(plan);
    ASSERT_TRUE(r.ok()) << r.error;
    EXPECT_GT(r.framing_errors, 0u);
    EXPECT_GT(r.unframed_bytes, 0u);
    bool named = false;
    for (const std::string& w : r.warnings)
        named = named ||
                w.find("the target looks like an HTTP server (\"HTTP/1.0 400") != std::string::npos;
    EXPECT_TRUE(named) << (r.warnings.empty() ? std::string("no warnings") : r.warnings.back());
}

}  // namespace
}  // namespace mbstorm::load
