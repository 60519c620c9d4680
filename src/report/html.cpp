#include "report/html.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>
#include <vector>

#include "report/explain.hpp"
#include "report/html_page.hpp"
#include "report/units.hpp"
#include "report/xml_escape.hpp"

namespace mbstorm::report {
namespace {

using stats::Histogram;
using stats::OutcomeCounters;

constexpr const char* kOverallColor = "#222222";

std::string escape(std::string_view text) {
    return xml_escape(text);
}

struct LatencyUnit {
    double divisor;
    const char* name;
};
LatencyUnit latency_unit(double max_ns) {
    if (max_ns < 1e6) return {1e3, "µs"};
    if (max_ns < 1e9) return {1e6, "ms"};
    return {1e9, "s"};
}

// 0%, 90%, 99%, 99.9%, ... for x = log10(1/(1-p)) = 0, 1, 2, 3, ...
std::string percentile_tick_label(int decade) {
    if (decade == 0) return "0%";
    if (decade == 1) return "90%";
    return "99" + (decade > 2 ? "." + std::string(static_cast<std::size_t>(decade - 2), '9') : "") +
           "%";
}

std::string percentile_chart(const stats::RunResult& r) {
    struct Line {
        std::string name;
        std::string color;
        const Histogram* histogram;
    };
    std::vector<Line> lines;
    lines.push_back({"all operations", kOverallColor, &r.latency});
    for (std::size_t i = 0; i < r.operations.size(); ++i) {
        lines.push_back(
            {r.operations[i].name, kPalette[i % kPalette.size()], &r.operations[i].latency});
    }

    Chart c;
    c.title = "Latency by percentile";
    c.x_label = "percentile";
    double max_x = 2.0, max_ns = 0.0;
    for (const auto& line : lines) {
        if (line.histogram->empty()) continue;
        Series s{line.name, line.color, {}, line.histogram == &r.latency ? 2.4 : 1.6};
        for (const auto& p : stats::percentile_distribution(*line.histogram)) {
            if (p.percentile >= 100.0) continue;  // 1/(1-p) is infinite there
            const double x = std::log10(1.0 / (1.0 - p.percentile / 100.0));
            s.points.emplace_back(x, static_cast<double>(p.value));
            max_x = std::max(max_x, x);
            max_ns = std::max(max_ns, static_cast<double>(p.value));
        }
        c.series.push_back(std::move(s));
    }
    const LatencyUnit unit = latency_unit(max_ns);
    for (auto& s : c.series) {
        for (auto& pt : s.points) pt.second /= unit.divisor;
    }
    c.x_min = 0.0;
    c.x_max = std::min(std::ceil(max_x - 1e-9), 7.0);
    for (int d = 0; d <= static_cast<int>(c.x_max); ++d)
        c.x_ticks.push_back({static_cast<double>(d), percentile_tick_label(d)});
    c.y_max = linear_ticks(max_ns / unit.divisor, c.y_ticks);
    c.y_label = fmt::format("latency ({})", unit.name);
    return render_chart(c);
}

void add_stage_markers(const stats::RunResult& r, Chart& c) {
    for (const auto& st : r.stages) {
        c.markers.push_back({static_cast<double>(st.start_offset_ns) / 1e9, st.name});
    }
}

double timeline_end_seconds(const stats::RunResult& r) {
    double end = static_cast<double>(r.metadata.measured_duration_ns) / 1e9;
    for (const auto& i : r.timeline) {
        end = std::max(end, static_cast<double>(i.start_offset_ns + i.duration_ns) / 1e9);
    }
    return end > 0.0 ? end : 1.0;
}

// Where an interval is plotted on the time axis.
double midpoint_seconds(const stats::IntervalSummary& i) {
    return (static_cast<double>(i.start_offset_ns) + i.duration_ns / 2.0) / 1e9;
}

std::string throughput_chart(const stats::RunResult& r) {
    Chart c;
    c.title = "Throughput over time";
    c.x_label = "time (s)";
    c.y_label = "transactions / s";
    Series tx{"transactions/s", kPalette[0], {}};
    Series errors{"errors/s", kPalette[1], {}};
    Series target{"target rate", kPalette[2], {}, 1.2};
    double max_rate = 0.0;
    for (const auto& i : r.timeline) {
        const double mid = midpoint_seconds(i);
        const double rate = i.transactions_per_second();
        const double error_rate =
            i.duration_ns == 0 ? 0.0 : static_cast<double>(i.errors) * 1e9 / i.duration_ns;
        tx.points.emplace_back(mid, rate);
        errors.points.emplace_back(mid, error_rate);
        target.points.emplace_back(mid, i.target_rate);
        max_rate = std::max({max_rate, rate, i.target_rate});
    }
    c.series.push_back(std::move(tx));
    c.series.push_back(std::move(errors));
    // Open loop: the offered rate next to what was achieved shows where the target fell behind.
    if (r.metadata.model == stats::LoadModel::Open) c.series.push_back(std::move(target));
    c.x_max = time_ticks(timeline_end_seconds(r), c.x_ticks);
    c.y_max = linear_ticks(max_rate, c.y_ticks);
    add_stage_markers(r, c);
    return render_chart(c);
}

// Staged runs: how many connections were open, so connection ramps can be read off.
std::string connections_chart(const stats::RunResult& r) {
    Chart c;
    c.title = "Open connections over time";
    c.x_label = "time (s)";
    c.y_label = "connections";
    Series open{"open connections", kPalette[2], {}};
    double max_open = 0.0;
    for (const auto& i : r.timeline) {
        const double mid = midpoint_seconds(i);
        open.points.emplace_back(mid, i.open_connections);
        max_open = std::max(max_open, static_cast<double>(i.open_connections));
    }
    c.series.push_back(std::move(open));
    c.x_max = time_ticks(timeline_end_seconds(r), c.x_ticks);
    c.y_max = linear_ticks(std::max(max_open, 1.0), c.y_ticks);
    add_stage_markers(r, c);
    return render_chart(c);
}

std::string latency_over_time_chart(const stats::RunResult& r) {
    Chart c;
    c.title = "Latency over time";
    c.x_label = "time (s)";
    double max_ns = 0.0;
    for (const auto& i : r.timeline) max_ns = std::max(max_ns, static_cast<double>(i.max_ns));
    const LatencyUnit unit = latency_unit(max_ns);
    c.y_label = fmt::format("latency ({})", unit.name);
    Series p50{"p50", kPalette[0], {}}, p99{"p99", kPalette[3], {}},
        max{"max", kPalette[1], {}, 1.2};
    for (const auto& i : r.timeline) {
        if (i.latency_count == 0) continue;
        const double mid = midpoint_seconds(i);
        p50.points.emplace_back(mid, static_cast<double>(i.p50_ns) / unit.divisor);
        p99.points.emplace_back(mid, static_cast<double>(i.p99_ns) / unit.divisor);
        max.points.emplace_back(mid, static_cast<double>(i.max_ns) / unit.divisor);
    }
    c.series.push_back(std::move(p50));
    c.series.push_back(std::move(p99));
    c.series.push_back(std::move(max));
    c.x_max = time_ticks(timeline_end_seconds(r), c.x_ticks);
    c.y_max = linear_ticks(max_ns / unit.divisor, c.y_ticks);
    add_stage_markers(r, c);
    return render_chart(c);
}

// ---------------------------------------------------------------- tables

std::string run_table(const stats::RunResult& r) {
    const auto& m = r.metadata;
    std::string t = "<table class=\"kv\">\n";
    auto kv = [&](const char* k, const std::string& v) { table_row(t, {k, escape(v)}); };
    kv("Target", m.target);
    kv("Load model", load_model_text(r));
    kv("Threads / connections / depth",
       fmt::format("{} / {} / {}", m.threads, m.connections, m.depth));
    kv("Duration",
       fmt::format("{} measured (requested {}), warm-up {}",
                   format_duration(m.measured_duration_ns),
                   format_duration(m.requested_duration_ns), format_duration(m.warmup_ns)));
    if (const auto start = format_utc(m.start_time); !start.empty()) kv("Started", start);
    if (m.coordinated_omission_corrected) kv("Latency", "corrected for coordinated omission");
    for (const auto& note : m.notes) kv("Note", note);
    t += "</table>\n";
    return t;
}

std::string summary_table(const stats::RunResult& r) {
    const auto& c = r.counters;
    std::string t = "<table class=\"kv\">\n";
    auto kv = [&](const char* k, const std::string& v) { table_row(t, {k, escape(v)}); };
    kv("Throughput", format_rate(r.throughput()) + " transactions/s");
    kv("Transactions", fmt::format("{} completed, {} sent", format_count(c.completed()),
                                   format_count(c.transactions_sent)));
    kv("Errors", fmt::format("{} ({:.3f}%)", format_count(c.errors()),
                             c.completed() == 0 ? 0.0 : 100.0 * c.errors() / c.completed()));
    if (c.stray_responses() != 0)
        kv("Stray responses", fmt::format("{} answered no transaction (discarded)",
                                          format_count(c.stray_responses())));
    kv("Traffic", fmt::format("sent {}, received {}", format_bytes(c.bytes_sent),
                              format_bytes(c.bytes_received)));
    kv("Connections",
       fmt::format("opened {}, failed {}, reconnects {}, closed by peer {}", r.connections.opened,
                   r.connections.failed, r.connections.reconnects, r.connections.closed_by_peer));
    for (const auto& line : schedule_lines(r)) kv("Schedule", line);
    for (const auto& s : r.shortfalls) {
        table_row(t, {"Plan", "<span class=\"bad\">NOT carried out</span>: " + escape(s.text)});
    }
    for (const auto& hint : hint_lines(r)) kv("Hint", hint);
    t += "</table>\n";
    return t;
}

// `target`: the per-stage table's scheduled rate column (absent elsewhere).
void latency_row(std::string& t, const std::string& name, const Histogram& h,
                 std::uint64_t completed, double seconds, const std::string* target = nullptr) {
    const double rate = seconds > 0.0 ? static_cast<double>(completed) / seconds : 0.0;
    auto p = [&](double q) {
        return h.empty() ? std::string("-") : format_latency(h.value_at_percentile(q));
    };
    std::vector<std::string> cells = {escape(name)};
    if (target != nullptr) cells.push_back(escape(*target));
    for (auto& cell : {format_count(completed), format_rate(rate), p(50), p(75), p(90), p(99),
                       p(99.9), p(99.99), p(99.999), h.empty() ? "-" : format_latency(h.max()),
                       h.empty() ? "-" : format_latency(h.mean())})
        cells.push_back(cell);
    table_row(t, cells);
}

void latency_header(std::string& t, const char* first, bool with_target = false) {
    std::vector<std::string> cells = {first};
    if (with_target) cells.emplace_back("target/s");
    for (const char* cell :
         {"count", "tx/s", "p50", "p75", "p90", "p99", "p99.9", "p99.99", "p99.999", "max", "mean"})
        cells.emplace_back(cell);
    table_row(t, cells, true);
}

std::string latency_table(const stats::RunResult& r) {
    const double seconds = static_cast<double>(r.metadata.measured_duration_ns) / 1e9;
    std::string t = "<div class=\"scroll\"><table>\n";
    latency_header(t, "operation");
    latency_row(t, "all operations", r.latency, r.counters.completed(), seconds);
    for (const auto& op : r.operations) {
        latency_row(t, format_operation(op.name, op.function_code), op.latency,
                    op.counters.completed(), seconds);
    }
    // Open loop: the rows above count from the intended send; this one from the actual send.
    if (r.metadata.model == stats::LoadModel::Open && r.service_time.total_count() != 0)
        latency_row(t, "service time, uncorrected (all operations, from the actual send)",
                    r.service_time, r.service_time.total_count(), seconds);
    t += "</table></div>\n";
    return t;
}

std::string errors_table(const stats::RunResult& r) {
    if (r.counters.errors() == 0 && r.counters.stray_responses() == 0)
        return "<p class=\"ok\">No errors.</p>\n";
    std::string t = "<table>\n<tr><th class=\"l\">error</th><th>all</th>";
    for (const auto& op : r.operations) t += fmt::format("<th>{}</th>", escape(op.name));
    t += "</tr>\n";
    auto emit = [&](const std::string& label, bool indented, auto count_of) {
        t += fmt::format("<tr><td class=\"l{}\">{}</td><td>{}</td>", indented ? " sub" : "",
                         escape(label), format_count(count_of(r.counters)));
        for (const auto& op : r.operations)
            t += fmt::format("<td>{}</td>", format_count(count_of(op.counters)));
        t += "</tr>\n";
    };
    for (std::size_t i = 1; i < stats::kOutcomeCount; ++i) {
        const auto outcome = static_cast<stats::Outcome>(i);
        if (r.counters.count(outcome) == 0) continue;
        const std::string name(stats::outcome_name(outcome));
        emit(stats::is_stray(outcome) ? name + " (stray response)" : name, false,
             [outcome](const OutcomeCounters& c) { return c.count(outcome); });
        if (outcome != stats::Outcome::Exception) continue;
        for (std::size_t code = 0; code < 256; ++code) {
            if (r.counters.exceptions[code] == 0) continue;
            emit("exception " + format_exception_code(static_cast<std::uint8_t>(code)), true,
                 [code](const OutcomeCounters& c) { return c.exceptions[code]; });
        }
    }
    t += "</table>\n";
    return t;
}

std::string stages_table(const stats::RunResult& r) {
    std::string t = "<div class=\"scroll\"><table>\n";
    const bool open = r.metadata.model == stats::LoadModel::Open;
    latency_header(t, "stage", open);
    const std::string no_target;
    for (const auto& st : r.stages) {
        const double seconds = static_cast<double>(st.end_offset_ns - st.start_offset_ns) / 1e9;
        const std::string target = stage_rate_text(st, r.metadata.model);
        latency_row(t,
                    fmt::format("{}. {} ({:.1f}s–{:.1f}s)", st.index, st.name,
                                static_cast<double>(st.start_offset_ns) / 1e9,
                                static_cast<double>(st.end_offset_ns) / 1e9),
                    st.latency, st.counters.completed(), seconds, open ? &target : nullptr);
        for (const auto& op : st.operations) {
            latency_row(t, "    " + format_operation(op.name, op.function_code), op.latency,
                        op.counters.completed(), seconds, open ? &no_target : nullptr);
        }
    }
    t += "</table></div>\n";
    return t;
}

std::string thresholds_table(const stats::RunResult& r) {
    std::string t = "<table>\n";
    table_row(t, {"threshold", "observed", "result"}, true);
    for (const auto& th : r.thresholds) {
        table_row(
            t, {escape(th.expression),
                escape(th.observed_text.empty() ? trim_number(th.observed) : th.observed_text),
                th.passed ? "<span class=\"ok\">PASS</span>" : "<span class=\"bad\">FAIL</span>"});
    }
    t += "</table>\n";
    return t;
}

}  // namespace

std::string format_html(const stats::RunResult& r) {
    const auto& m = r.metadata;
    std::string out;
    out += page_start("mbstorm report — " + m.target);
    out +=
        fmt::format("<h1>mbstorm load report</h1>\n<p class=\"sub\">{} · {} · {}</p>\n",
                    escape(m.target), escape(m.tool_version.empty() ? "mbstorm" : m.tool_version),
                    escape(format_utc(m.start_time)));

    out += "<h2>Run</h2>\n" + run_table(r);
    out += "<h2>Summary</h2>\n" + summary_table(r);
    if (!r.thresholds.empty()) {
        out += fmt::format("<h2>Thresholds — <span class=\"{}\">{}</span></h2>\n",
                           r.thresholds_passed() ? "ok" : "bad",
                           r.thresholds_passed() ? "all passed" : "failed");
        out += thresholds_table(r);
    }
    out += "<h2>Latency</h2>\n" + latency_table(r);
    out += percentile_chart(r);
    if (!r.timeline.empty()) {
        out += "<h2>Over time</h2>\n";
        out += throughput_chart(r);
        out += latency_over_time_chart(r);
        if (!r.stages.empty()) out += connections_chart(r);
    }
    if (!r.stages.empty()) out += "<h2>Stages</h2>\n" + stages_table(r);
    out += "<h2>Errors</h2>\n" + errors_table(r);
    out += page_end();
    return out;
}

}  // namespace mbstorm::report
