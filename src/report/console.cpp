#include "report/console.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <string_view>
#include <utility>

#include "report/explain.hpp"

namespace mbstorm::report {
namespace {

using stats::Histogram;
using stats::OutcomeCounters;

constexpr std::array<std::pair<double, const char*>, 7> kConsolePercentiles = {
    {{50.0, "p50"},
     {75.0, "p75"},
     {90.0, "p90"},
     {99.0, "p99"},
     {99.9, "p99.9"},
     {99.99, "p99.99"},
     {99.999, "p99.999"}}};

// fmt pads by code points, so "µs" (two bytes, one column) lines up.
void append_latency_table(std::string& out, const Histogram& h) {
    if (h.empty()) {
        out += "  (no latency samples)\n";
        return;
    }
    for (const auto& [p, label] : kConsolePercentiles) {
        out += fmt::format("  {:<9}{:>10}\n", label, format_latency(h.value_at_percentile(p)));
    }
    out += fmt::format("  {:<9}{:>10}\n", "max", format_latency(h.max()));
    out += fmt::format("  {:<9}{:>10}   stddev {}   min {}\n", "mean", format_latency(h.mean()),
                       format_latency(h.stddev()), format_latency(h.min()));
    if (h.saturated_count() != 0) {
        out +=
            fmt::format("  note: {} samples above {} were clamped to it\n",
                        format_count(h.saturated_count()), format_latency(h.highest_trackable()));
    }
}

void append_error_lines(std::string& out, const OutcomeCounters& c, const char* indent) {
    for (std::size_t i = 1; i < stats::kOutcomeCount; ++i) {
        const auto outcome = static_cast<stats::Outcome>(i);
        if (c.count(outcome) == 0 || stats::is_stray(outcome)) continue;
        out += fmt::format("{}{:<22}{:>14}\n", indent, stats::outcome_name(outcome),
                           format_count(c.count(outcome)));
        if (outcome == stats::Outcome::Exception) {
            for (std::size_t code = 0; code < c.exceptions.size(); ++code) {
                if (c.exceptions[code] == 0) continue;
                out += fmt::format("{}  {:<33}{:>14}\n", indent,
                                   format_exception_code(static_cast<std::uint8_t>(code)),
                                   format_count(c.exceptions[code]));
            }
        }
    }
}

double percent(std::uint64_t part, std::uint64_t whole) {
    return whole == 0 ? 0.0 : 100.0 * static_cast<double>(part) / static_cast<double>(whole);
}

// The first column is as wide as its longest label (at least 33): names are never cut. The
// per-stage table has a second one, the rate the schedule asked for (`target`; empty: none).
constexpr std::size_t kTargetWidth = 16;

void append_row_header(std::string& out, const char* first, std::size_t width,
                       bool with_target = false) {
    out += fmt::format("  {:<{}}{:>{}}{:>12}{:>10}{:>9}{:>10}{:>10}{:>10}{:>10}{:>10}\n", first,
                       width, with_target ? "target/s" : "", with_target ? kTargetWidth : 0,
                       "count", "tx/s", "errors", "p50", "p90", "p99", "p99.9", "max");
}

void append_row(std::string& out, std::size_t width, const std::string& name, const Histogram& h,
                const OutcomeCounters& c, double seconds, const std::string* target = nullptr) {
    const double rate = seconds > 0.0 ? static_cast<double>(c.completed()) / seconds : 0.0;
    out += fmt::format(
        "  {:<{}}{:>{}}{:>12}{:>10}{:>9}{:>10}{:>10}{:>10}{:>10}{:>10}\n", name, width,
        target != nullptr ? *target : std::string(), target != nullptr ? kTargetWidth : 0,
        format_count(c.completed()), format_rate(rate), format_count(c.errors()),
        format_latency(h.value_at_percentile(50)), format_latency(h.value_at_percentile(90)),
        format_latency(h.value_at_percentile(99)), format_latency(h.value_at_percentile(99.9)),
        format_latency(h.max()));
}

std::string operation_label(const stats::OperationResult& op) {
    return format_operation(op.name, op.function_code);
}

std::string stage_label(const stats::StageResult& st) {
    return fmt::format("{}. {}", st.index, st.name);
}

constexpr std::string_view kStageOperationIndent = "   ";

std::size_t label_width(const stats::RunResult& r) {
    std::size_t width = 32;
    for (const auto& op : r.operations) width = std::max(width, operation_label(op).size());
    for (const auto& st : r.stages) {
        width = std::max(width, stage_label(st).size());
        for (const auto& op : st.operations)
            width = std::max(width, kStageOperationIndent.size() + operation_label(op).size());
    }
    return width + 1;
}

// TLS handshakes and who carried the records, when the run used TLS.
void append_tls_lines(std::string& out, const stats::ConnectionStats& cs, double seconds) {
    if (cs.tls_handshakes == 0) return;
    out += fmt::format(
        "TLS         {} handshakes ({:.0f}/s), {} resumed, {} failed, latency mean {:.3f} ms, "
        "max {:.3f} ms\n",
        format_count(cs.tls_handshakes),
        static_cast<double>(cs.tls_handshakes) / (seconds > 0 ? seconds : 1.0),
        format_count(cs.tls_resumed), format_count(cs.tls_handshake_failures),
        static_cast<double>(cs.tls_handshake_ns_total) / static_cast<double>(cs.tls_handshakes) /
            1e6,
        static_cast<double>(cs.tls_handshake_ns_max) / 1e6);
    out += fmt::format(
        "            records by kernel TLS on {} connections ({} ended by a non-data "
        "record), by userspace OpenSSL on {}\n",
        format_count(cs.tls_offloaded), format_count(cs.tls_offload_errors),
        format_count(cs.tls_handshakes - cs.tls_offloaded));
}

}  // namespace

std::string format_console_report(const stats::RunResult& r) {
    const auto& m = r.metadata;
    const double seconds = static_cast<double>(m.measured_duration_ns) / 1e9;
    std::string out;

    out += fmt::format("{} — {} loop against {}\n",
                       m.tool_version.empty() ? "mbstorm" : m.tool_version,
                       stats::load_model_name(m.model), m.target);
    out += fmt::format("  threads {}, connections {}, depth {}", m.threads, m.connections, m.depth);
    if (!m.backend.empty()) out += fmt::format(", {}", m.backend);
    if (m.model == stats::LoadModel::Open) out += fmt::format(", {}", load_model_text(r));
    out += fmt::format(", duration {} (warm-up {})\n", format_duration(m.measured_duration_ns),
                       format_duration(m.warmup_ns));
    if (const auto start = format_utc(m.start_time); !start.empty()) {
        out += fmt::format("  started {}\n", start);
    }
    if (m.coordinated_omission_corrected) out += "  latencies corrected for coordinated omission\n";
    for (const auto& note : m.notes) out += fmt::format("  note: {}\n", note);

    const auto& c = r.counters;
    out += fmt::format("\nThroughput  {} tx/s  ({} transactions in {:.2f}s, {} sent)\n",
                       format_rate(r.throughput()), format_count(c.completed()), seconds,
                       format_count(c.transactions_sent));
    out += fmt::format("Traffic     sent {}, received {}\n", format_bytes(c.bytes_sent),
                       format_bytes(c.bytes_received));
    std::string causes;
    for (const auto& [name, count] : r.connections.failed_by_cause)
        causes += fmt::format("{}{} {}", causes.empty() ? " (" : ", ", name, format_count(count));
    if (!causes.empty()) causes += ")";
    out += fmt::format("Connections opened {}, failed {}{}, reconnects {}, closed by peer {}\n",
                       format_count(r.connections.opened), format_count(r.connections.failed),
                       causes, format_count(r.connections.reconnects),
                       format_count(r.connections.closed_by_peer));
    append_tls_lines(out, r.connections, seconds);
    for (const auto& line : schedule_lines(r)) out += fmt::format("Schedule    {}\n", line);
    if (!r.shortfalls.empty()) {
        out += "Plan        NOT carried out:\n";
        for (const auto& s : r.shortfalls) out += fmt::format("  {}\n", s.text);
    }

    const bool open_loop = r.metadata.model == stats::LoadModel::Open;
    out += fmt::format("\nLatency ({} samples{})\n", format_count(r.latency.total_count()),
                       open_loop ? "; from each request's intended send, queueing included" : "");
    append_latency_table(out, r.latency);
    if (open_loop && r.service_time.total_count() != 0) {
        out += fmt::format(
            "\nService time, uncorrected ({} samples; from each request's actual send: what the "
            "target took, without the wait the schedule saw)\n",
            format_count(r.service_time.total_count()));
        append_latency_table(out, r.service_time);
    }

    out += fmt::format("\nErrors      {} of {} ({:.3f}%)\n", format_count(c.errors()),
                       format_count(c.completed()), percent(c.errors(), c.completed()));
    append_error_lines(out, c, "  ");
    if (c.stray_responses() != 0) {
        out += fmt::format(
            "Stray       {} responses answered no transaction (unknown_id {}, duplicate_id {}); "
            "discarded\n",
            format_count(c.stray_responses()), format_count(c.count(stats::Outcome::UnknownId)),
            format_count(c.count(stats::Outcome::DuplicateId)));
    }
    for (const auto& hint : hint_lines(r)) out += fmt::format("Hint        {}\n", hint);

    const std::size_t width = label_width(r);
    if (!r.operations.empty()) {
        out += "\nPer operation\n";
        append_row_header(out, "operation (function)", width);
        for (const auto& op : r.operations) {
            append_row(out, width, operation_label(op), op.latency, op.counters, seconds);
        }
    }

    if (!r.stages.empty()) {
        out += "\nPer stage\n";
        const bool open = m.model == stats::LoadModel::Open;
        append_row_header(out, "stage", width, open);
        const std::string no_target;
        for (const auto& st : r.stages) {
            const double stage_seconds =
                static_cast<double>(st.end_offset_ns - st.start_offset_ns) / 1e9;
            const std::string target = stage_rate_text(st, m.model);
            append_row(out, width, stage_label(st), st.latency, st.counters, stage_seconds,
                       open ? &target : nullptr);
            for (const auto& op : st.operations) {
                append_row(out, width, std::string(kStageOperationIndent) + operation_label(op),
                           op.latency, op.counters, stage_seconds, open ? &no_target : nullptr);
            }
        }
    }

    if (!r.thresholds.empty()) {
        out += fmt::format("\nThresholds  {}\n", r.thresholds_passed() ? "all passed" : "FAILED");
        for (const auto& t : r.thresholds) {
            out += fmt::format(
                "  {}  {:<36} observed {}\n", t.passed ? "PASS" : "FAIL", t.expression,
                t.observed_text.empty() ? fmt::format("{}", t.observed) : t.observed_text);
        }
    }
    return out;
}

std::string format_progress_line(const ProgressSample& s) {
    std::string line = fmt::format("[{:>7.1f}s]", s.elapsed_seconds);
    if (s.last_interval != nullptr) {
        const auto& i = *s.last_interval;
        line += fmt::format("  {:>6} tx/s  p50 {:>7}  p99 {:>7}  max {:>7}",
                            format_rate(i.transactions_per_second()), format_latency(i.p50_ns),
                            format_latency(i.p99_ns), format_latency(i.max_ns));
    } else {
        line += fmt::format("  {:>6} tx/s  p50 {:>7}  p99 {:>7}  max {:>7}", "-", "-", "-", "-");
    }
    line += fmt::format("  errors {}  conns {}", format_count(s.total_errors), s.open_connections);
    return line;
}

ProgressPrinter::ProgressPrinter(std::FILE* out)
    : ProgressPrinter(out, out != nullptr && ::isatty(::fileno(out)) == 1) {}

ProgressPrinter::ProgressPrinter(std::FILE* out, bool is_tty) : out_(out), is_tty_(is_tty) {}

void ProgressPrinter::update(const ProgressSample& sample) {
    if (out_ == nullptr) return;
    const std::string line = format_progress_line(sample);
    if (is_tty_) {
        // Pad with spaces so a shorter line fully covers the previous one.
        const std::size_t pad = last_width_ > line.size() ? last_width_ - line.size() : 0;
        std::fprintf(out_, "\r%s%*s", line.c_str(), static_cast<int>(pad), "");
        last_width_ = line.size();
        line_open_ = true;
    } else {
        std::fprintf(out_, "%s\n", line.c_str());
    }
    std::fflush(out_);
}

void ProgressPrinter::finish() {
    if (out_ == nullptr || !line_open_) return;
    std::fputc('\n', out_);
    std::fflush(out_);
    line_open_ = false;
    last_width_ = 0;
}

}  // namespace mbstorm::report
