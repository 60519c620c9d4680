#include "report/html_page.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "report/xml_escape.hpp"

namespace mbstorm::report {
namespace {

constexpr double kWidth = 900, kHeight = 360;
constexpr double kLeft = 78, kRight = 40, kTop = 34, kBottom = 52;

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
.wrap { display: inline-block; min-width: 24em; white-space: normal; text-align: left; }
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

std::string escape(std::string_view text) {
    return xml_escape(text);
}

}  // namespace

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
double linear_ticks(double max, std::vector<Tick>& ticks, const std::string& suffix) {
    const double step = nice_step(max, 5);
    const double top = std::max(step, std::ceil(max / step - 1e-9) * step);
    for (double v = 0.0; v <= top + step * 1e-6; v += step) {
        ticks.push_back({v, trim_number(v) + suffix});
    }
    return top;
}

namespace {

// Data coordinates to SVG coordinates inside the plot area.
struct Plot {
    const Chart& c;
    double w = kWidth - kLeft - kRight;
    double h = kHeight - kTop - kBottom;
    double x(double v) const {
        const double span = c.x_max > c.x_min ? c.x_max - c.x_min : 1.0;
        return kLeft + (v - c.x_min) / span * w;
    }
    double y(double v) const {
        const double span = c.y_max > c.y_min ? c.y_max - c.y_min : 1.0;
        return kTop + h - (v - c.y_min) / span * h;
    }
};

std::string render_grid(const Plot& p) {
    std::string s = "<g class=\"grid\">\n";
    for (const auto& t : p.c.y_ticks) {
        const double y = p.y(t.at);
        s += fmt::format("<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\"/>\n", kLeft,
                         y, kLeft + p.w, y);
        s += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" class=\"ylab\">{}</text>\n", kLeft - 6,
                         y + 4, escape(t.label));
    }
    for (const auto& t : p.c.x_ticks) {
        const double x = p.x(t.at);
        s += fmt::format("<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\"/>\n", x,
                         kTop, x, kTop + p.h);
        s += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" class=\"xlab\">{}</text>\n", x,
                         kTop + p.h + 16, escape(t.label));
    }
    s += "</g>\n";
    s += fmt::format(
        "<rect x=\"{}\" y=\"{}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"none\" "
        "stroke=\"#888888\"/>\n",
        kLeft, kTop, p.w, p.h);
    for (const auto& m : p.c.markers) {
        const double x = p.x(m.at);
        s += fmt::format(
            "<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" class=\"marker\"/>\n", x,
            kTop, x, kTop + p.h);
        s += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" class=\"mlab\">{}</text>\n", x + 3,
                         kTop + 12, escape(m.label));
    }
    return s;
}

std::string render_series(const Plot& p) {
    std::string s;
    for (const auto& series : p.c.series) {
        if (series.points.empty()) continue;
        std::string pts;
        for (const auto& [x, y] : series.points) {
            pts += fmt::format("{:.1f},{:.1f} ", p.x(std::clamp(x, p.c.x_min, p.c.x_max)),
                               p.y(std::clamp(y, p.c.y_min, p.c.y_max)));
        }
        if (!pts.empty()) pts.pop_back();
        s += fmt::format(
            "<polyline fill=\"none\" stroke=\"{}\" stroke-width=\"{}\" "
            "stroke-linejoin=\"round\" points=\"{}\"><title>{}</title></polyline>\n",
            series.color, series.width, pts, escape(series.name));
    }
    return s;
}

std::string render_legend(const Chart& c) {
    std::string s = "<div class=\"legend\">";
    for (const auto& series : c.series) {
        s += fmt::format("<span><i style=\"background:{}\"></i>{}</span>", series.color,
                         escape(series.name));
    }
    s += "</div>\n";
    return s;
}

}  // namespace

std::string render_chart(const Chart& c) {
    const Plot p{c};
    std::string s = fmt::format(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 {} {}\" width=\"{}\" "
        "height=\"{}\" role=\"img\" aria-label=\"{}\">\n",
        kWidth, kHeight, kWidth, kHeight, escape(c.title));
    s += fmt::format("<rect x=\"0\" y=\"0\" width=\"{}\" height=\"{}\" fill=\"#ffffff\"/>\n",
                     kWidth, kHeight);
    s += fmt::format("<text x=\"{}\" y=\"20\" class=\"title\">{}</text>\n", kLeft, escape(c.title));
    s += render_grid(p);
    s += render_series(p);
    s += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" class=\"axis\">{}</text>\n", kLeft + p.w / 2,
                     kHeight - 10, escape(c.x_label));
    s += fmt::format(
        "<text x=\"16\" y=\"{:.1f}\" class=\"axis\" transform=\"rotate(-90 16 "
        "{:.1f})\">{}</text>\n",
        kTop + p.h / 2, kTop + p.h / 2, escape(c.y_label));
    s += "</svg>\n";
    return s + render_legend(c);
}

void table_row(std::string& out, const std::vector<std::string>& cells, bool header) {
    out += "<tr>";
    bool first = true;
    for (const auto& cell : cells) {
        const char* tag = header ? "th" : "td";
        out += fmt::format("<{}{}>{}</{}>", tag, first ? " class=\"l\"" : "", cell, tag);
        first = false;
    }
    out += "</tr>\n";
}

std::string page_start(std::string_view title) {
    std::string out = "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
    out += "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n";
    out += fmt::format("<title>{}</title>\n", escape(title));
    out += fmt::format("<style>{}</style>\n</head>\n<body>\n<main>\n", kStyle);
    return out;
}

std::string page_end() {
    return "</main>\n</body>\n</html>\n";
}

}  // namespace mbstorm::report
