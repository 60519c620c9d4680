// The Prometheus text exposition of run's live metrics: format, escaping, cumulative buckets.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <map>
#include <regex>
#include <sstream>
#include <string>

#include "report/prometheus.hpp"

namespace mbstorm::report {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

std::vector<std::string> lines_of(const std::string& text) {
    std::vector<std::string> lines;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) lines.push_back(line);
    return lines;
}

stats::LiveLoad sample_live() {
    stats::LiveLoad live;
    live.test_id = "soak \"A\"\\1";
    live.running = true;
    stats::LiveOperation op;
    op.name = "read";
    op.function_code = 0x03;
    op.unit_id = 7;
    op.counters.transactions_sent = 12;
    op.counters.outcomes[static_cast<std::size_t>(stats::Outcome::Ok)] = 9;
    op.counters.outcomes[static_cast<std::size_t>(stats::Outcome::Exception)] = 2;
    op.counters.exceptions[0x02] = 2;
    op.counters.outcomes[static_cast<std::size_t>(stats::Outcome::Timeout)] = 1;
    op.counters.bytes_sent = 144;
    op.latency_buckets[0] = 3;                           // <= 25 us
    op.latency_buckets[5] = 6;                           // <= 1 ms
    op.latency_buckets[stats::kLatencyBuckets - 1] = 2;  // above 10 s
    op.latency_sum_ns = 25'000'000'000;
    live.operations.push_back(op);
    live.open_connections = 4;
    live.target_rate = 1000;
    live.achieved_rate = 998.5;
    live.tls = {.handshakes = 4,
                .resumed = 1,
                .handshake_failures = 2,
                .handshake_ns_total = 6'000'000,
                .offloaded = 3,
                .offload_errors = 1};
    return live;
}

TEST(Prometheus, EscapesLabelValuesAndHelp) {
    EXPECT_EQ(escape_label_value("a\"b\\c\nd"), "a\\\"b\\\\c\\nd");
    EXPECT_EQ(escape_help("a\"b\\c\nd"), "a\"b\\\\c\\nd");
}

TEST(Prometheus, BoundsAreExactDecimalSeconds) {
    EXPECT_EQ(seconds_text(25'000), "0.000025");
    EXPECT_EQ(seconds_text(2'500'000), "0.0025");
    EXPECT_EQ(seconds_text(1'000'000'000), "1");
    EXPECT_EQ(seconds_text(2'500'000'000), "2.5");
    EXPECT_EQ(seconds_text(0), "0");
}

TEST(Prometheus, EveryLineIsACommentOrASampleOfADeclaredFamily) {
    const std::string text = format_load_metrics(sample_live());
    const std::regex sample(
        R"(^([a-zA-Z_:][a-zA-Z0-9_:]*)(\{([a-zA-Z_][a-zA-Z0-9_]*="([^"\\]|\\.)*",?)*\})? (-?[0-9.e+]+|\+Inf|NaN)$)");
    const std::regex type(R"(^# TYPE ([a-zA-Z_:][a-zA-Z0-9_:]*) (counter|gauge|histogram)$)");
    std::map<std::string, std::string> types;
    ASSERT_FALSE(text.empty());
    EXPECT_EQ(text.back(), '\n');
    for (const std::string& line : lines_of(text)) {
        std::smatch m;
        if (std::regex_match(line, m, type)) {
            EXPECT_EQ(types.count(m[1]), 0u) << "declared twice: " << line;
            types[m[1]] = m[2];
            continue;
        }
        if (line.rfind("# HELP ", 0) == 0) continue;
        ASSERT_TRUE(std::regex_match(line, m, sample)) << line;
        std::string family = m[1];
        for (const char* suffix : {"_bucket", "_sum", "_count"}) {
            const std::string s = suffix;
            if (family.size() > s.size() && family.ends_with(s) &&
                types.count(family.substr(0, family.size() - s.size())) != 0)
                family = family.substr(0, family.size() - s.size());
        }
        ASSERT_EQ(types.count(family), 1u) << "sample before its TYPE: " << line;
        if (types[family] == "counter") {
            EXPECT_TRUE(family.ends_with("_total")) << family;
        }
    }
    // Never a percentile: they cannot be added across runs.
    EXPECT_THAT(text, Not(HasSubstr("quantile")));
    EXPECT_THAT(text, Not(HasSubstr("p99")));
}

TEST(Prometheus, LoadMetricsCarryTheirLabelsAndCounts) {
    const std::string text = format_load_metrics(sample_live());
    const std::string labels =
        R"(test="soak \"A\"\\1",operation="read",function="read_holding_registers",unit="7")";
    EXPECT_THAT(text, HasSubstr("mbstorm_transactions_total{" + labels + R"(,outcome="ok"} 9)"));
    EXPECT_THAT(text,
                HasSubstr("mbstorm_transactions_total{" + labels + R"(,outcome="timeout"} 1)"));
    EXPECT_THAT(text, HasSubstr("mbstorm_exceptions_total{" + labels + R"(,exception="0x02"} 2)"));
    EXPECT_THAT(text, HasSubstr("mbstorm_requests_sent_total{" + labels + "} 12"));
    EXPECT_THAT(text, HasSubstr("mbstorm_sent_bytes_total{" + labels + "} 144"));
    EXPECT_THAT(text, HasSubstr(R"(mbstorm_open_connections{test="soak \"A\"\\1"} 4)"));
    EXPECT_THAT(text, HasSubstr("mbstorm_achieved_transactions_per_second{"));
    EXPECT_THAT(text, HasSubstr("} 998.5\n"));
    EXPECT_THAT(text, HasSubstr("# TYPE mbstorm_transaction_latency_seconds histogram\n"));
}

// run's TLS counters are serve's names with run's prefix and labels: one list serves both.
TEST(Prometheus, TlsCountersAreNamedAlikeForRunAndServe) {
    const std::string run = format_load_metrics(sample_live());
    const std::string labels = R"({test="soak \"A\"\\1"})";
    EXPECT_THAT(run, HasSubstr("mbstorm_tls_handshakes_total" + labels + " 4\n"));
    EXPECT_THAT(run, HasSubstr("mbstorm_tls_resumptions_total" + labels + " 1\n"));
    EXPECT_THAT(run, HasSubstr("mbstorm_tls_handshake_failures_total" + labels + " 2\n"));
    EXPECT_THAT(run, HasSubstr("mbstorm_tls_offloaded_total" + labels + " 3\n"));
    EXPECT_THAT(run, HasSubstr("mbstorm_tls_offload_errors_total" + labels + " 1\n"));
    EXPECT_THAT(run, HasSubstr("mbstorm_tls_handshake_seconds_total" + labels + " 0.006\n"));

    PrometheusWriter w;
    write_tls_counters(w, "mbstorm_slave_", {}, {4, 1, 2, 3, 1});
    const std::string serve = w.text();
    for (const char* name :
         {"tls_handshakes_total", "tls_resumptions_total", "tls_handshake_failures_total",
          "tls_offloaded_total", "tls_offload_errors_total"}) {
        const std::string family = std::string("# TYPE mbstorm_slave_") + name + " counter\n";
        EXPECT_THAT(serve, HasSubstr(family));
        EXPECT_THAT(run, HasSubstr(std::string("# TYPE mbstorm_") + name + " counter\n"));
    }
    EXPECT_THAT(serve, HasSubstr("mbstorm_slave_tls_handshakes_total 4\n"));
    EXPECT_THAT(serve, HasSubstr("mbstorm_slave_tls_handshake_failures_total 2\n"));
}

// A shard of a distributed run labels every series with its index, after the test, so that
// sum without (shard) is the whole test.
TEST(Prometheus, AShardLabelsEverySeriesWithItsIndex) {
    stats::LiveLoad live = sample_live();
    live.test_id = "t";
    live.shard = "2";
    const std::string text = format_load_metrics(live);
    EXPECT_THAT(text, HasSubstr(R"(mbstorm_open_connections{test="t",shard="2"} 4)"));
    EXPECT_THAT(text, HasSubstr(R"(mbstorm_running{test="t",shard="2"} )"));
    EXPECT_THAT(text,
                HasSubstr(R"(mbstorm_requests_sent_total{test="t",shard="2",operation="read",)"
                          R"(function="read_holding_registers",unit="7"} 12)"));
    EXPECT_THAT(text, HasSubstr(R"(mbstorm_stray_responses_total{test="t",shard="2",outcome=)"));
}

TEST(Prometheus, NoTestIdMeansNoTestLabel) {
    stats::LiveLoad live = sample_live();
    live.test_id.clear();
    const std::string text = format_load_metrics(live);
    EXPECT_THAT(text, Not(HasSubstr("test=")));
    EXPECT_THAT(text, HasSubstr("mbstorm_open_connections 4\n"));
}

TEST(Prometheus, BucketsAreCumulativeAndInfEqualsCount) {
    const std::string text = format_load_metrics(sample_live());
    const std::regex bucket(
        "^mbstorm_transaction_latency_seconds_bucket\\{.*,le=\"([^\"]+)\"\\} ([0-9]+)$");
    std::vector<std::pair<std::string, std::uint64_t>> buckets;
    std::uint64_t count = 0;
    double sum = -1;
    for (const std::string& line : lines_of(text)) {
        std::smatch m;
        if (std::regex_match(line, m, bucket)) buckets.emplace_back(m[1], std::stoull(m[2]));
        if (line.rfind("mbstorm_transaction_latency_seconds_count{", 0) == 0)
            count = std::stoull(line.substr(line.rfind(' ') + 1));
        if (line.rfind("mbstorm_transaction_latency_seconds_sum{", 0) == 0)
            sum = std::stod(line.substr(line.rfind(' ') + 1));
    }
    ASSERT_EQ(buckets.size(), stats::kLatencyBuckets);
    for (std::size_t i = 1; i < buckets.size(); ++i) {
        EXPECT_GE(buckets[i].second, buckets[i - 1].second) << buckets[i].first;
        if (i + 1 < buckets.size()) {
            EXPECT_LT(std::stod(buckets[i - 1].first), std::stod(buckets[i].first));
        }
    }
    EXPECT_EQ(buckets.front(), (std::pair<std::string, std::uint64_t>{"0.000025", 3}));
    EXPECT_EQ(buckets[5], (std::pair<std::string, std::uint64_t>{"0.001", 9}));
    EXPECT_EQ(buckets[buckets.size() - 2].second, 9u);
    EXPECT_EQ(buckets.back(), (std::pair<std::string, std::uint64_t>{"+Inf", 11}));
    EXPECT_EQ(count, 11u);
    EXPECT_DOUBLE_EQ(sum, 25.0);
}

TEST(Prometheus, WriterSkipsEmptyLabelsAndFormatsSpecialValues) {
    PrometheusWriter w;
    w.family("x_total", "counter", "a\nb");
    const PromLabel labels[] = {{"a", ""}, {"b", "v"}};
    w.sample("x_total", labels, std::uint64_t{3});
    w.sample("y", {}, std::numeric_limits<double>::infinity());
    w.sample("z", {}, std::numeric_limits<double>::quiet_NaN());
    EXPECT_EQ(w.text(),
              "# HELP x_total a\\nb\n# TYPE x_total counter\nx_total{b=\"v\"} 3\ny +Inf\nz NaN\n");
}

}  // namespace
}  // namespace mbstorm::report
