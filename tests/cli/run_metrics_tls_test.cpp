// run --metrics-listen over --transport tls: the engine's live endpoint (the one `run` starts:
// start_metrics_endpoint serving format_load_metrics of the live totals) carries the TLS
// counters while the run goes, with serve's names under run's prefix, and after the run the
// report's numbers. Against the in-process reference slave, on loopback.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <openssl/ssl.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <memory>
#include <string>
#include <thread>

#include "../support/tls_test_support.hpp"
#include "cli/metrics_endpoint.hpp"
#include "load/engine.hpp"
#include "load/live_metrics.hpp"
#include "net/http_server.hpp"
#include "report/prometheus.hpp"
#include "server/server.hpp"

namespace mbstorm::cli {
namespace {

using namespace std::chrono_literals;

// GET /metrics from the endpoint at "127.0.0.1:PORT": the whole response, "" when it cannot
// connect (each read bounded by a 2 s timeout).
std::string scrape(const std::string& address) {
    const auto colon = address.rfind(':');
    sockaddr_in to{};
    to.sin_family = AF_INET;
    to.sin_port = htons(static_cast<std::uint16_t>(std::stoi(address.substr(colon + 1))));
    to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd < 0) return {};
    const timeval limit{2, 0};
    ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &limit, sizeof limit);
    std::string response;
    if (::connect(fd, reinterpret_cast<const sockaddr*>(&to), sizeof to) == 0) {
        const std::string request = "GET /metrics HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n";
        if (::send(fd, request.data(), request.size(), MSG_NOSIGNAL) ==
            static_cast<ssize_t>(request.size())) {
            char buf[4096];
            // EINTR is no end: io_uring's task work for rings this thread submitted to (the
            // slave's, the engine's) interrupts a recv that has a timeout.
            for (ssize_t n; (n = ::recv(fd, buf, sizeof buf, 0)) > 0 || (n < 0 && errno == EINTR);)
                if (n > 0) response.append(buf, n);
        }
    }
    ::close(fd);
    return response;
}

// The value of the sample `series` (name and labels) in an exposition; -1 when it is not
// there (every value here is a count, a sum of durations or a 0/1 gauge).
double sample(const std::string& text, const std::string& series) {
    const std::string key = "\n" + series + " ";
    const auto at = text.find(key);
    return at == std::string::npos ? -1.0 : std::stod(text.substr(at + key.size()));
}

class RunMetricsTls : public test::TlsCertsTest {
  protected:
    // The reference slave on a free loopback port, serving TLS with the server certificate.
    bool start_slave() {
        server::ServerConfig config;
        config.listen = "127.0.0.1:0";
        config.threads = 1;
        config.tls = context(net::TlsSide::Server, "server");
        if (!config.tls) return false;
        slave_ = std::make_unique<server::Server>(config);
        const Error error = slave_->start();
        EXPECT_TRUE(error.ok()) << error.text();
        return error.ok();
    }
    // The endpoint `run --metrics-listen 127.0.0.1:0` starts for `live`.
    static bool start_endpoint(net::HttpServer& http, load::LiveMetrics& live) {
        return start_metrics_endpoint(http, "127.0.0.1:0", "run", [&live] {
            return report::format_load_metrics(live.snapshot());
        });
    }
    static load::Plan tls_plan(std::uint16_t port) {
        load::Plan plan;
        plan.host = "127.0.0.1";
        plan.port = port;
        load::Operation op;
        op.function = 0x03;
        op.last_address = 99;
        op.quantity = 2;
        plan.operations = {op};
        plan.threads = 1;
        plan.connections = 3;
        plan.depth = 1;
        return plan;
    }

    std::unique_ptr<server::Server> slave_;

    // A run whose client certificate (of another CA) the slave refuses, the live endpoint up:
    // its result and what the endpoint said after it (labelled test=`label`).
    struct RefusedRun {
        load::LoadResult result;
        std::string scraped;
    };
    RefusedRun run_refused(int tls_version, const std::string& label) {
        RefusedRun out;
        if (!start_slave()) return out;
        load::Plan plan = tls_plan(slave_->port());
        plan.tls = context(net::TlsSide::Client, "rogue", tls_version);
        if (!plan.tls) return out;
        plan.duration = 5s;  // ended by the refusal at once
        load::LiveMetrics live(label);
        net::HttpServer http;
        if (!start_endpoint(http, live)) return out;
        load::EngineOptions options;
        options.live = &live;
        out.result = load::run_load(plan, options);
        out.scraped = scrape(http.address());
        return out;
    }
};

TEST_F(RunMetricsTls, TheLiveEndpointCountsHandshakesWhileTheRunGoesAndEndsAtTheReport) {
    ASSERT_TRUE(start_slave());
    load::Plan plan = tls_plan(slave_->port());
    plan.tls = context(net::TlsSide::Client, "operator");
    ASSERT_TRUE(plan.tls);
    plan.model = load::LoadModel::OpenLoop;
    plan.rate = 300;
    plan.duration = 1500ms;
    load::LiveMetrics live("tls-live");
    net::HttpServer http;
    ASSERT_TRUE(start_endpoint(http, live));

    const std::string labels = R"({test="tls-live"})";
    auto value = [&](const std::string& text, const char* name) {
        return sample(text, std::string(name) + labels);
    };
    std::atomic<bool> done{false};
    std::string during;  // a scrape taken while the run went, with every connection open
    std::thread scraper([&] {
        // Bounded: 300 scrapes 10 ms apart at the most, whatever happens to the run.
        for (int i = 0; i < 300 && !done.load(); ++i) {
            const std::string text = scrape(http.address());
            if (value(text, "mbstorm_running") == 1.0 &&
                value(text, "mbstorm_open_connections") == 3.0) {
                during = text;
                return;
            }
            std::this_thread::sleep_for(10ms);
        }
    });
    load::EngineOptions options;
    options.live = &live;
    const load::LoadResult r = load::run_load(plan, options);
    done = true;
    scraper.join();
    ASSERT_TRUE(r.ok()) << r.error;
    ASSERT_FALSE(during.empty()) << "no scrape saw the run going with its 3 connections open";

    EXPECT_EQ(value(during, "mbstorm_tls_handshakes_total"), 3.0);
    EXPECT_EQ(value(during, "mbstorm_tls_resumptions_total"), 0.0);
    EXPECT_EQ(value(during, "mbstorm_tls_handshake_failures_total"), 0.0);
    EXPECT_EQ(value(during, "mbstorm_tls_offload_errors_total"), 0.0);
    const double offloaded = value(during, "mbstorm_tls_offloaded_total");
    EXPECT_GE(offloaded, 0.0);
    EXPECT_LE(offloaded, 3.0);
    const double handshake_seconds = value(during, "mbstorm_tls_handshake_seconds_total");
    EXPECT_GT(handshake_seconds, 0.0);
    EXPECT_LT(handshake_seconds, 3 * 10.0);  // within the connect timeout each

    // After the run: the report's numbers.
    const std::string after = scrape(http.address());
    const stats::ConnectionStats& c = r.run.connections;
    EXPECT_EQ(value(after, "mbstorm_running"), 0.0);
    EXPECT_EQ(value(after, "mbstorm_tls_handshakes_total"), static_cast<double>(c.tls_handshakes));
    EXPECT_EQ(value(after, "mbstorm_tls_resumptions_total"), static_cast<double>(c.tls_resumed));
    EXPECT_EQ(value(after, "mbstorm_tls_offloaded_total"), static_cast<double>(c.tls_offloaded));
    EXPECT_EQ(value(after, "mbstorm_tls_offload_errors_total"),
              static_cast<double>(c.tls_offload_errors));
    EXPECT_NEAR(value(after, "mbstorm_tls_handshake_seconds_total"),
                static_cast<double>(c.tls_handshake_ns_total) / 1e9, 1e-6);
}

// A client certificate of another CA: the slave refuses it at the handshake (TLS 1.2, where
// the refusal ends the client's own handshake), which the endpoint counts as a failure.
TEST_F(RunMetricsTls, ARefusedHandshakeIsCountedAsAFailure) {
    const auto [r, text] = run_refused(TLS1_2_VERSION, "tls-refused");
    EXPECT_FALSE(r.ok());
    EXPECT_NE(r.error.message().find("TLS handshake failed"), std::string::npos) << r.error;
    const std::string labels = R"({test="tls-refused"})";
    const double failures = sample(text, "mbstorm_tls_handshake_failures_total" + labels);
    EXPECT_GE(failures, 1.0) << text;
    EXPECT_LE(failures, 3.0);
    EXPECT_EQ(sample(text, "mbstorm_tls_handshakes_total" + labels), 0.0);
    EXPECT_EQ(sample(text, "mbstorm_connections_failed_total" + labels), failures);
    // The report counts them as the endpoint did.
    EXPECT_EQ(static_cast<double>(r.run.connections.tls_handshake_failures), failures);
}

// Under TLS 1.3 the client's handshake ends before the slave has checked its certificate: the
// refusal comes as an alert after it, before any answer. It is a handshake failure all the same.
TEST_F(RunMetricsTls, ACertificateRefusedAfterATls13HandshakeIsCountedAsAFailure) {
    const auto [r, text] = run_refused(TLS1_3_VERSION, "tls13-refused");
    EXPECT_FALSE(r.ok());
    EXPECT_NE(r.error.message().find("TLS session refused"), std::string::npos) << r.error;
    EXPECT_GE(r.run.connections.tls_handshake_failures, 1u);
    EXPECT_EQ(sample(text, R"(mbstorm_tls_handshake_failures_total{test="tls13-refused"})"),
              static_cast<double>(r.run.connections.tls_handshake_failures))
        << text;
}

}  // namespace
}  // namespace mbstorm::cli
