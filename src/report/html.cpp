#include "report/html.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>
#include <vector>

#include "report/explain.hpp"
#include "report/units.hpp"
#include "report/xml_escape.hpp"

namespace mbstorm::report {
namespace {

using stats::Histogram;
using stats::OutcomeCounters;

constexpr std::array<const char*, 8> kPalette = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e",
                                                 "#9467bd", "#8c564b", "#e377c2", "#17becf"};
constexpr const char* kOverallColor = "#222222";

std::string escape(std::string_view text) {
    return xml_escape(text);
}

// ---------------------------------------------------------------- charts (inline SVG)

struct Series {
    std::string name;
    std::string color;
    std::vector<std::pair<double, double>> points;  // data coordinates
    double width = 1.8;
};
struct Tick {
    double at;
    std::string label;
};
struct Chart {
    std::string title;
    std::string x_label;
    std::string y_label;
    double x_min = 0, x_max = 1, y_min = 0, y_max = 1;
    std::vector<Tick> x_ticks, y_ticks;
    std::vector<Series> series;
    std::vector<Tick> markers;  // vertical lines (stage boundaries)
};

constexpr double kWidth = 900, kHeight = 360;
constexpr double kLeft = 78, kRight = 40, kTop = 34, kBottom = 52;

// A "nice" step (1, 2, 2.5, 5 x 10^n) giving about `target` intervals up to max.
double nice_step(double max, int target) {
    if (!(max > 0.0)) return 1.0;
    const double raw = max / target;
    const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
    for (double m : {1.0, 2.0, 2.5, 5.0, 10.0}) {
        if (m * magnitude >= raw) return m * magnitude;
    }
    return 10.0 * magnitude;
}

std::string trim_number(double v) {
    std::string s = fmt::format("{:.3f}", v);
    while (!s.empty() && s.back() == '0') s.pop_back();
    if (!s.empty() && s.back() == '.') s.pop_back();
    return s;
}

// Time axis 0..end: nice ticks up to the run's end, which is where the axis ends (a 3 s run
// is not drawn to 4 s).
double time_ticks(double end, std::vector<Tick>& ticks) {
    const double step = nice_step(end, 5);
    for (double v = 0.0; v <= end + step * 1e-6; v += step) ticks.push_back({v, trim_number(v)});
    return end;
}

// Linear 0..max axis with nice ticks; returns the rounded-up max.
double linear_ticks(double max, std::vector<Tick>& ticks, const std::string& suffix = "") {
    const double step = nice_step(max, 5);
    const double top = std::max(step, std::ceil(max / step - 1e-9) * step);
    for (double v = 0.0; v <= top + step * 1e-6; v += step) {
        ticks.push_back({v, trim_number(v) + suffix});
    }
    return top;
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

std::string render_chart(const Chart& c) {
    const double plot_w = kWidth - kLeft - kRight;
    const double plot_h = kHeight - kTop - kBottom;
    const double x_span = c.x_max > c.x_min ? c.x_max - c.x_min : 1.0;
    const double y_span = c.y_max > c.y_min ? c.y_max - c.y_min : 1.0;
    auto px = [&](double x) { return kLeft + (x - c.x_min) / x_span * plot_w; };
    auto py = [&](double y) { return kTop + plot_h - (y - c.y_min) / y_span * plot_h; };

    std::string s = fmt::format(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 {} {}\" width=\"{}\" "
        "height=\"{}\" role=\"img\" aria-label=\"{}\">\n",
        kWidth, kHeight, kWidth, kHeight, escape(c.title));
    s += fmt::format("<rect x=\"0\" y=\"0\" width=\"{}\" height=\"{}\" fill=\"#ffffff\"/>\n",
                     kWidth, kHeight);
    s += fmt::format("<text x=\"{}\" y=\"20\" class=\"title\">{}</text>\n", kLeft, escape(c.title));

    s += "<g class=\"grid\">\n";
    for (const auto& t : c.y_ticks) {
        const double y = py(t.at);
        s += fmt::format("<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\"/>\n", kLeft,
                         y, kLeft + plot_w, y);
        s += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" class=\"ylab\">{}</text>\n", kLeft - 6,
                         y + 4, escape(t.label));
    }
    for (const auto& t : c.x_ticks) {
        const double x = px(t.at);
        s += fmt::format("<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\"/>\n", x,
                         kTop, x, kTop + plot_h);
        s += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" class=\"xlab\">{}</text>\n", x,
                         kTop + plot_h + 16, escape(t.label));
    }
    s += "</g>\n";
    s += fmt::format(
        "<rect x=\"{}\" y=\"{}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"none\" "
        "stroke=\"#888888\"/>\n",
        kLeft, kTop, plot_w, plot_h);

    for (const auto& m : c.markers) {
        const double x = px(m.at);
        s += fmt::format(
            "<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" class=\"marker\"/>\n", x,
            kTop, x, kTop + plot_h);
        s += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" class=\"mlab\">{}</text>\n", x + 3,
                         kTop + 12, escape(m.label));
    }

    for (const auto& series : c.series) {
        if (series.points.empty()) continue;
        std::string pts;
        for (const auto& [x, y] : series.points) {
            pts += fmt::format("{:.1f},{:.1f} ", px(std::clamp(x, c.x_min, c.x_max)),
                               py(std::clamp(y, c.y_min, c.y_max)));
        }
        if (!pts.empty()) pts.pop_back();
        s += fmt::format(
            "<polyline fill=\"none\" stroke=\"{}\" stroke-width=\"{}\" "
            "stroke-linejoin=\"round\" points=\"{}\"><title>{}</title></polyline>\n",
            series.color, series.width, pts, escape(series.name));
    }

    s += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" class=\"axis\">{}</text>\n",
                     kLeft + plot_w / 2, kHeight - 10, escape(c.x_label));
    s += fmt::format(
        "<text x=\"16\" y=\"{:.1f}\" class=\"axis\" transform=\"rotate(-90 16 "
        "{:.1f})\">{}</text>\n",
        kTop + plot_h / 2, kTop + plot_h / 2, escape(c.y_label));
    s += "</svg>\n";

    s += "<div class=\"legend\">";
    for (const auto& series : c.series) {
        s += fmt::format("<span><i style=\"background:{}\"></i>{}</span>", series.color,
                         escape(series.name));
    }
    s += "</div>\n";
    return s;
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

void row(std::string& out, const std::vector<std::string>& cells, bool header = false) {
    out += "<tr>";
    bool first = true;
    for (const auto& cell : cells) {
        const char* tag = header ? "th" : "td";
        out += fmt::format("<{}{}>{}</{}>", tag, first ? " class=\"l\"" : "", cell, tag);
        first = false;
    }
    out += "</tr>\n";
}

std::string run_table(const stats::RunResult& r) {
    const auto& m = r.metadata;
    std::string t = "<table class=\"kv\">\n";
    auto kv = [&](const char* k, const std::string& v) { row(t, {k, escape(v)}); };
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
    auto kv = [&](const char* k, const std::string& v) { row(t, {k, escape(v)}); };
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
        row(t, {"Plan", "<span class=\"bad\">NOT carried out</span>: " + escape(s.text)});
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
    row(t, cells);
}

void latency_header(std::string& t, const char* first, bool with_target = false) {
    std::vector<std::string> cells = {first};
    if (with_target) cells.emplace_back("target/s");
    for (const char* cell :
         {"count", "tx/s", "p50", "p75", "p90", "p99", "p99.9", "p99.99", "p99.999", "max", "mean"})
        cells.emplace_back(cell);
    row(t, cells, true);
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
    row(t, {"threshold", "observed", "result"}, true);
    for (const auto& th : r.thresholds) {
        row(t, {escape(th.expression),
                escape(th.observed_text.empty() ? trim_number(th.observed) : th.observed_text),
                th.passed ? "<span class=\"ok\">PASS</span>" : "<span class=\"bad\">FAIL</span>"});
    }
    t += "</table>\n";
    return t;
}

constexpr const char* kStyle = R"css(
body { font-family: system-ui, -apple-system, "Segoe UI", Roboto, "Helvetica Neue", Arial, sans-serif;
       color: #1d1d1f; background: #f6f7f9; margin: 0; line-height: 1.45; }
main { max-width: 940px; margin: 0 auto; padding: 24px 20px 60px; }
h1 { font-size: 1.6em; margin: 0 0 4px; }
h2 { font-size: 1.15em; margin: 32px 0 10px; border-bottom: 1px solid #d9dce1; padding-bottom: 4px; }
.sub { color: #5a6270; margin: 0 0 16px; }
section.card { background: #fff; border: 1px solid #e1e4e8; border-radius: 6px; padding: 12px 16px; }
table { border-collapse: collapse; width: 100%; font-size: 0.86em; background: #fff;
        font-variant-numeric: tabular-nums; }
th, td { padding: 5px 6px; border-bottom: 1px solid #eceef1; text-align: right; white-space: nowrap; }
th { background: #f0f2f5; font-weight: 600; }
.l { text-align: left; }
td.sub { padding-left: 24px; }
.scroll { overflow-x: auto; }
table.kv td.l { width: 32%; color: #5a6270; }
table.kv td { text-align: left; white-space: normal; }
.ok { color: #1a7f37; font-weight: 600; }
.bad { color: #cf222e; font-weight: 600; }
svg { display: block; margin-top: 14px; max-width: 100%; height: auto; background: #fff; border: 1px solid #e1e4e8;
      border-radius: 6px; font-family: inherit; }
svg .title { font-size: 14px; font-weight: 600; fill: #1d1d1f; }
svg .grid line { stroke: #e6e8eb; stroke-width: 1; }
svg .ylab { font-size: 11px; fill: #5a6270; text-anchor: end; }
svg .xlab { font-size: 11px; fill: #5a6270; text-anchor: middle; }
svg .axis { font-size: 12px; fill: #3c4350; text-anchor: middle; }
svg .marker { stroke: #8250df; stroke-width: 1.2; stroke-dasharray: 5 4; }
svg .mlab { font-size: 11px; fill: #8250df; }
.legend { margin: 6px 0 18px; font-size: 0.88em; color: #3c4350; }
.legend span { margin-right: 16px; white-space: nowrap; }
.legend i { display: inline-block; width: 14px; height: 3px; margin-right: 6px; vertical-align: middle; }
)css";

}  // namespace

std::string format_html(const stats::RunResult& r) {
    const auto& m = r.metadata;
    std::string out;
    out += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
    out += "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n";
    out += fmt::format("<title>mbstorm report — {}</title>\n", escape(m.target));
    out += fmt::format("<style>{}</style>\n</head>\n<body>\n<main>\n", kStyle);
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
    out += "</main>\n</body>\n</html>\n";
    return out;
}

}  // namespace mbstorm::report
