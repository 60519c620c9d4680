// Pieces of mbstorm's self-contained HTML pages (run --html, fuzz --html): inline-SVG line
// charts, table rows and the page's style. No scripts, no external fetches.
#pragma once

#include <array>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace mbstorm::report {

inline constexpr std::array<const char*, 8> kPalette = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e",
                                                        "#9467bd", "#8c564b", "#e377c2", "#17becf"};

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

// The chart as inline SVG, followed by its legend.
std::string render_chart(const Chart& c);

// A "nice" step (1, 2, 2.5, 5 x 10^n) giving about `target` intervals up to max.
double nice_step(double max, int target);
// `v` with at most three decimals and no trailing zeros.
std::string trim_number(double v);
// Time axis 0..end: nice ticks up to `end`, which is where the axis ends; returns `end`.
double time_ticks(double end, std::vector<Tick>& ticks);
// Linear 0..max axis with nice ticks; returns the rounded-up max.
double linear_ticks(double max, std::vector<Tick>& ticks, const std::string& suffix = "");

// A table row of cells already escaped; the first cell is left-aligned.
void table_row(std::string& out, const std::vector<std::string>& cells, bool header = false);

// The page up to <main> (doctype, title, style) and from </main> to the end.
std::string page_start(std::string_view title);
std::string page_end();

}  // namespace mbstorm::report
