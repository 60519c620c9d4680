// Prometheus text exposition format (version 0.0.4), for `--metrics-listen`:
//
//   # HELP mbstorm_transactions_total Transactions that ended, by outcome.
//   # TYPE mbstorm_transactions_total counter
//   mbstorm_transactions_total{function="read_holding_registers",unit="1",outcome="ok"} 1234
//   mbstorm_transaction_latency_seconds_bucket{...,le="0.001"} 1200
//
// Counters are in base units (seconds, bytes) and end in _total; latency is a histogram of
// cumulative buckets with fixed bounds (stats/latency_buckets.hpp), so that the series of
// many runs add up; no percentile is exported (percentiles cannot be added).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "stats/live_metrics.hpp"

namespace mbstorm::report {

inline constexpr std::string_view kPrometheusContentType =
    "text/plain; version=0.0.4; charset=utf-8";

struct PromLabel {
    std::string_view name;
    std::string_view value;
};
using PromLabels = std::span<const PromLabel>;

// A label value with \, " and newline escaped as the format asks.
std::string escape_label_value(std::string_view value);
// HELP text: \ and newline escaped.
std::string escape_help(std::string_view help);

// Builds one exposition: a family's HELP and TYPE lines, then its samples.
class PrometheusWriter {
  public:
    // type: counter, gauge or histogram.
    void family(std::string_view name, std::string_view type, std::string_view help);
    void sample(std::string_view name, PromLabels labels, std::uint64_t value);
    void sample(std::string_view name, PromLabels labels, double value);
    // name_bucket{le=...} cumulative over per_bucket (one more count than bounds: the last is
    // above every bound, +Inf), then name_sum (sum_ns in seconds) and name_count.
    void histogram(std::string_view name, PromLabels labels,
                   std::span<const std::uint64_t> bounds_ns,
                   std::span<const std::uint64_t> per_bucket, std::uint64_t sum_ns);
    const std::string& text() const noexcept { return text_; }

  private:
    void labels_and_value(PromLabels labels, std::string_view value);
    std::string text_;
};

// "0.000025", "1", "2.5": a bound in nanoseconds as seconds, shortest exact form.
std::string seconds_text(std::uint64_t ns);

// The TLS counters `run` and `serve` both export (--transport tls; zero on other transports),
// named prefix + "tls_handshakes_total" and so on: one list of names and meanings for both.
struct PromTlsCounters {
    std::uint64_t handshakes = 0;
    std::uint64_t resumptions = 0;
    std::uint64_t handshake_failures = 0;
    std::uint64_t offloaded = 0;
    std::uint64_t offload_errors = 0;
};
// prefix: "mbstorm_" (run) or "mbstorm_slave_" (serve).
void write_tls_counters(PrometheusWriter& w, std::string_view prefix, PromLabels labels,
                        const PromTlsCounters& tls);

// `mbstorm run`'s metrics (names: docs/metrics.md).
std::string format_load_metrics(const stats::LiveLoad& live);

}  // namespace mbstorm::report
