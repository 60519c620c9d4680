#include "report/prometheus.hpp"

#include <fmt/format.h>

#include <cmath>
#include <iterator>
#include <utility>

#include "codec/exception_code.hpp"
#include "codec/function_code.hpp"

namespace mbstorm::report {
namespace {

std::string escaped(std::string_view text, bool quotes) {
    std::string out;
    out.reserve(text.size());
    for (const char c : text) {
        if (c == '\\') {
            out += "\\\\";
        } else if (c == '\n') {
            out += "\\n";
        } else if (c == '"' && quotes) {
            out += "\\\"";
        } else {
            out += c;
        }
    }
    return out;
}

std::string number_text(double value) {
    if (std::isnan(value)) return "NaN";
    if (std::isinf(value)) return value > 0 ? "+Inf" : "-Inf";
    return fmt::format("{}", value);
}

}  // namespace

std::string escape_label_value(std::string_view value) {
    return escaped(value, true);
}

std::string escape_help(std::string_view help) {
    return escaped(help, false);
}

std::string seconds_text(std::uint64_t ns) {
    // Integer arithmetic: 25'000 ns is "0.000025" exactly, never 2.4999e-05.
    std::string text = fmt::format("{}.{:09}", ns / 1'000'000'000, ns % 1'000'000'000);
    while (text.back() == '0') text.pop_back();
    if (text.back() == '.') text.pop_back();
    return text;
}

void PrometheusWriter::family(std::string_view name, std::string_view type, std::string_view help) {
    text_ += fmt::format("# HELP {} {}\n# TYPE {} {}\n", name, escape_help(help), name, type);
}

void PrometheusWriter::labels_and_value(PromLabels labels, std::string_view value) {
    bool first = true;
    for (const PromLabel& label : labels) {
        if (label.value.empty()) continue;  // an empty value is the same as no label
        text_ += first ? '{' : ',';
        first = false;
        text_ += label.name;
        text_ += "=\"";
        text_ += escape_label_value(label.value);
        text_ += '"';
    }
    if (!first) text_ += '}';
    text_ += ' ';
    text_ += value;
    text_ += '\n';
}

void PrometheusWriter::sample(std::string_view name, PromLabels labels, std::uint64_t value) {
    text_ += name;
    labels_and_value(labels, fmt::format("{}", value));
}

void PrometheusWriter::sample(std::string_view name, PromLabels labels, double value) {
    text_ += name;
    labels_and_value(labels, number_text(value));
}

void PrometheusWriter::histogram(std::string_view name, PromLabels labels,
                                 std::span<const std::uint64_t> bounds_ns,
                                 std::span<const std::uint64_t> per_bucket, std::uint64_t sum_ns) {
    std::vector<PromLabel> with_le(labels.begin(), labels.end());
    with_le.push_back({"le", ""});
    const std::string bucket = fmt::format("{}_bucket", name);
    std::uint64_t cumulative = 0;
    for (std::size_t i = 0; i < per_bucket.size(); ++i) {
        cumulative += per_bucket[i];
        const std::string le = i < bounds_ns.size() ? seconds_text(bounds_ns[i]) : "+Inf";
        with_le.back().value = le;
        sample(bucket, with_le, cumulative);
    }
    sample(fmt::format("{}_sum", name), labels, static_cast<double>(sum_ns) / 1e9);
    sample(fmt::format("{}_count", name), labels, cumulative);
}

namespace {

std::string function_label(std::uint8_t fc) {
    const std::string_view name = codec::function_name(fc);
    return name.empty() ? fmt::format("0x{:02x}", fc) : std::string(name);
}

}  // namespace

void write_tls_counters(PrometheusWriter& w, std::string_view prefix, PromLabels labels,
                        const PromTlsCounters& tls) {
    const std::pair<const char*, const char*> families[] = {
        {"tls_handshakes_total", "TLS handshakes completed."},
        {"tls_resumptions_total", "TLS handshakes that resumed a session."},
        // (No userspace counter: handshakes minus offloaded would go down at each hand-off.)
        {"tls_offloaded_total",
         "TLS connections handed to the kernel's TLS after the handshake (the other "
         "handshakes' records stay in userspace OpenSSL)."},
        {"tls_offload_errors_total",
         "Offloaded TLS connections ended by a record the kernel does not pass as data."},
        {"tls_handshake_failures_total",
         "TLS connections that ended at the handshake: refused (certificate, role), a protocol "
         "error, or (run) no handshake within the connect timeout."},
    };
    const std::uint64_t values[] = {tls.handshakes, tls.resumptions, tls.offloaded,
                                    tls.offload_errors, tls.handshake_failures};
    for (std::size_t i = 0; i < std::size(families); ++i) {
        const std::string name = fmt::format("{}{}", prefix, families[i].first);
        w.family(name, "counter", families[i].second);
        w.sample(name, labels, values[i]);
    }
}

namespace {

// Every operation's series: the run's labels plus its operation, function and unit, in one
// fixed order.
class OperationSeries {
  public:
    OperationSeries(const stats::LiveLoad& live, const std::vector<PromLabel>& run_labels)
        : live_(live), run_labels_(run_labels) {
        for (const auto& op : live.operations) {
            functions_.push_back(function_label(op.function_code));
            units_.push_back(fmt::format("{}", op.unit_id));
        }
    }
    template <class Emit>
    void each(Emit&& emit) const {
        for (std::size_t i = 0; i < live_.operations.size(); ++i) {
            std::vector<PromLabel> labels = run_labels_;
            labels.push_back({"operation", live_.operations[i].name});
            labels.push_back({"function", functions_[i]});
            labels.push_back({"unit", units_[i]});
            emit(live_.operations[i], PromLabels(labels));
        }
    }

  private:
    const stats::LiveLoad& live_;
    const std::vector<PromLabel>& run_labels_;
    // Label values are views: the strings they view live here.
    std::vector<std::string> functions_, units_;
};

std::vector<PromLabel> with(PromLabels base, PromLabel extra) {
    std::vector<PromLabel> all(base.begin(), base.end());
    all.push_back(extra);
    return all;
}

// Requests sent, transactions by outcome and exception code, and the responses that answered
// none.
void write_outcome_families(PrometheusWriter& w, const stats::LiveLoad& live,
                            const OperationSeries& ops, PromLabels run_only) {
    w.family("mbstorm_requests_sent_total", "counter",
             "Requests sent after warm-up (each one a transaction once it ends).");
    ops.each([&](const stats::LiveOperation& op, PromLabels labels) {
        w.sample("mbstorm_requests_sent_total", labels, op.counters.transactions_sent);
    });
    w.family("mbstorm_transactions_total", "counter",
             "Transactions that ended, by outcome (ok, or the class of error: exception, "
             "timeout, connection_closed, ...).");
    ops.each([&](const stats::LiveOperation& op, PromLabels labels) {
        for (std::size_t i = 0; i < stats::kOutcomeCount; ++i) {
            const auto outcome = static_cast<stats::Outcome>(i);
            if (stats::is_stray(outcome)) continue;
            w.sample("mbstorm_transactions_total",
                     with(labels, {"outcome", stats::outcome_name(outcome)}),
                     op.counters.count(outcome));
        }
    });
    w.family("mbstorm_exceptions_total", "counter",
             "Exception responses, by exception code (also counted as outcome=\"exception\").");
    ops.each([&](const stats::LiveOperation& op, PromLabels labels) {
        for (std::size_t code = 0; code < op.counters.exceptions.size(); ++code) {
            if (op.counters.exceptions[code] == 0) continue;
            const std::string text = fmt::format("0x{:02x}", code);
            w.sample("mbstorm_exceptions_total", with(labels, {"exception", text}),
                     op.counters.exceptions[code]);
        }
    });
    w.family("mbstorm_stray_responses_total", "counter",
             "Responses that answered no transaction (unknown or duplicate transaction id).");
    for (const auto outcome : {stats::Outcome::UnknownId, stats::Outcome::DuplicateId}) {
        const auto labels = with(run_only, {"outcome", stats::outcome_name(outcome)});
        w.sample("mbstorm_stray_responses_total", labels, live.stray.count(outcome));
    }
}

void write_traffic_families(PrometheusWriter& w, const OperationSeries& ops) {
    w.family("mbstorm_sent_bytes_total", "counter", "Request bytes sent after warm-up (ADUs).");
    ops.each([&](const stats::LiveOperation& op, PromLabels labels) {
        w.sample("mbstorm_sent_bytes_total", labels, op.counters.bytes_sent);
    });
    w.family("mbstorm_received_bytes_total", "counter",
             "Response bytes received for transactions sent after warm-up (ADUs).");
    ops.each([&](const stats::LiveOperation& op, PromLabels labels) {
        w.sample("mbstorm_received_bytes_total", labels, op.counters.bytes_received);
    });
    w.family("mbstorm_transaction_latency_seconds", "histogram",
             "Latency of answered transactions (open loop: from the intended send time).");
    ops.each([&](const stats::LiveOperation& op, PromLabels labels) {
        w.histogram("mbstorm_transaction_latency_seconds", labels, stats::kLatencyBucketBoundsNs,
                    op.latency_buckets, op.latency_sum_ns);
    });
}

void write_connection_families(PrometheusWriter& w, const stats::LiveLoad& live,
                               PromLabels run_only) {
    w.family("mbstorm_connections_opened_total", "counter",
             "Connections opened (reconnects included).");
    w.sample("mbstorm_connections_opened_total", run_only, live.connections_opened);
    w.family("mbstorm_connections_failed_total", "counter", "Connect attempts that failed.");
    w.sample("mbstorm_connections_failed_total", run_only, live.connections_failed);
    w.family("mbstorm_connections_closed_total", "counter", "Connections closed by the target.");
    w.sample("mbstorm_connections_closed_total", run_only, live.connections_closed_by_peer);
    w.family("mbstorm_open_connections", "gauge", "Connections open now.");
    w.sample("mbstorm_open_connections", run_only, live.open_connections);
    w.family("mbstorm_in_flight_requests", "gauge",
             "Requests sent and not yet answered or timed out.");
    w.sample("mbstorm_in_flight_requests", run_only, live.in_flight);
    w.family("mbstorm_target_transactions_per_second", "gauge",
             "Open loop: the rate the plan asks for now (0 in closed loop).");
    w.sample("mbstorm_target_transactions_per_second", run_only, live.target_rate);
    w.family("mbstorm_achieved_transactions_per_second", "gauge",
             "Transactions that ended per second over the last full interval.");
    w.sample("mbstorm_achieved_transactions_per_second", run_only, live.achieved_rate);
    const stats::LiveTls& tls = live.tls;
    write_tls_counters(
        w, "mbstorm_", run_only,
        {tls.handshakes, tls.resumed, tls.handshake_failures, tls.offloaded, tls.offload_errors});
    w.family("mbstorm_tls_handshake_seconds_total", "counter",
             "Time from TCP connect to TLS handshake done, summed over the completed handshakes "
             "(divided by mbstorm_tls_handshakes_total: the mean).");
    w.sample("mbstorm_tls_handshake_seconds_total", run_only,
             static_cast<double>(tls.handshake_ns_total) / 1e9);
}

}  // namespace

std::string format_load_metrics(const stats::LiveLoad& live) {
    PrometheusWriter w;
    // On every series: the test and, for a shard of a distributed run, its index (so a sum
    // over `shard` is the whole test).
    std::vector<PromLabel> run_labels{{"test", live.test_id}};
    if (!live.shard.empty()) run_labels.push_back({"shard", live.shard});
    const PromLabels run_only(run_labels);
    const OperationSeries ops(live, run_labels);
    w.family("mbstorm_running", "gauge",
             "1 while the load test runs, 0 before it starts and after it ends.");
    w.sample("mbstorm_running", run_only, std::uint64_t{live.running ? 1u : 0u});
    write_outcome_families(w, live, ops, run_only);
    write_traffic_families(w, ops);
    write_connection_families(w, live, run_only);
    return w.text();
}

}  // namespace mbstorm::report
