// fuzz --html: the campaign as one page, with the load report's charts and style
// (report/html_page.hpp).
#include <fmt/format.h>

#include <algorithm>
#include <string>
#include <vector>

#include "codec/function_code.hpp"
#include "netfuzz/outputs.hpp"
#include "report/html_page.hpp"
#include "report/xml_escape.hpp"

namespace mbstorm::netfuzz {
namespace {

using report::table_row;
using report::xml_escape;

double cases_per_second(const CampaignResult& r) {
    return r.seconds > 0 ? static_cast<double>(r.cases) / r.seconds : 0.0;
}

std::string run_table(const CampaignResult& r, const RunInfo& info) {
    std::string t = "<table class=\"kv\">\n";
    auto kv = [&](const char* k, const std::string& v) { table_row(t, {k, xml_escape(v)}); };
    kv("Target", info.target);
    kv("Seed", fmt::format("{} ({} generator)", info.seed, info.naive ? "naive" : "structured"));
    kv("Duration", fmt::format("{:.1f} s", r.seconds));
    kv("Cases", fmt::format("{} ({:.0f} cases/s; {} batched, {} isolated runs)", r.cases,
                            cases_per_second(r), r.batched_cases, r.isolated_runs));
    kv("Stopped", r.stop_reason);
    kv("Target deaths", fmt::format("{} ({} restarts, {} not repeatable alone)", r.deaths,
                                    r.restarts, r.unattributed_deaths));
    kv("Repeats", fmt::format("{} cases showed a known root cause; {} skipped as a known "
                              "crash/hang; {} suspects unconfirmed",
                              r.duplicates, r.skipped_known, r.unconfirmed));
    if (r.coverage) {
        kv("Coverage", fmt::format("{} edges; corpus {} case(s); {} constant(s) from the "
                                   "target's comparisons",
                                   r.coverage_edges, r.corpus_size, r.compared_constants));
        if (r.resumed) kv("Corpus", fmt::format("resumed: {} saved entries run first", r.resumed));
        if (!r.corpus_error.empty()) kv("Corpus", "no longer saved: " + r.corpus_error);
    }
    if (r.target_lost) table_row(t, {"Target", "<span class=\"bad\">lost</span>"});
    t += "</table>\n";
    return t;
}

std::string ranges_text(const TableModel& tm) {
    std::string ranges;
    for (const AddressRange& a : tm.ranges)
        ranges += fmt::format(
            "{}{}", ranges.empty() ? "" : ", ",
            a.first == a.last ? fmt::format("{}", a.first) : fmt::format("{}-{}", a.first, a.last));
    return ranges.empty() ? "none" : ranges;
}

std::string model_section(const DeviceModel& m) {
    if (m.source.empty())
        return "<p>Not learned (<code>--no-model</code> or <code>--naive</code>).</p>\n";
    std::string t = fmt::format("<p class=\"sub\">{}{}</p>\n<table>\n", xml_escape(m.source),
                                m.partial ? ", partial (learning ran out of time)" : "");
    table_row(t, {"table", "addresses", "entries", "reads up to", "writes stick"}, true);
    for (std::size_t i = 0; i < kTableCount; ++i) {
        const auto table = static_cast<codec::Table>(i);
        const TableModel& tm = m.table(table);
        table_row(t, {xml_escape(std::string(table_label(table))), xml_escape(ranges_text(tm)),
                      fmt::format("{}", tm.entries()),
                      tm.max_quantity ? fmt::format("{}", tm.max_quantity) : "-",
                      xml_escape(std::string(writes_stick_name(tm.writes)))});
    }
    t += "</table>\n";
    std::string units;
    for (const std::uint8_t u : m.units) units += fmt::format("{}{}", units.empty() ? "" : ", ", u);
    if (!units.empty()) t += fmt::format("<p>Unit ids answering: {}</p>\n", units);
    return t;
}

std::string findings_section(const CampaignResult& r) {
    if (r.findings.empty()) return "<p class=\"ok\">No findings.</p>\n";
    std::string t = "<div class=\"scroll\"><table>\n";
    table_row(t,
              {"#", "kind", "root cause (oracle:rule)", "function", "hits", "confirmed",
               "minimised", "folder", "what"},
              true);
    for (const Finding& f : r.findings) {
        const std::string function =
            f.function() >= 0 ? codec::function_label(static_cast<std::uint8_t>(f.function()))
                              : std::string("-");
        const std::string kind = xml_escape(std::string(oracle_name(f.oracle())));
        const bool severe = f.oracle() == Oracle::Crash || f.oracle() == Oracle::Hang;
        table_row(
            t, {fmt::format("{}", f.id), severe ? "<span class=\"bad\">" + kind + "</span>" : kind,
                xml_escape(f.key()), xml_escape(function), fmt::format("{}", f.hits),
                f.confirmed ? "yes" : "no", f.minimized ? "yes" : "no",
                f.folder.empty() ? "(not saved)" : xml_escape(f.folder),
                "<span class=\"wrap\">" + xml_escape(f.verdict.summary) + "</span>"});
    }
    t += "</table></div>\n";
    return t;
}

// A step line: edges only grow, and stay where they are until the next point.
std::string edges_chart(const CampaignResult& r) {
    report::Chart c;
    c.title = "Edges reached over time";
    c.x_label = "time (s)";
    c.y_label = "edges";
    report::Series edges{"edges", report::kPalette[0], {{0.0, 0.0}}};
    double last = 0.0;
    for (const auto& [seconds, count] : r.edges_over_time) {
        edges.points.emplace_back(seconds, last);
        last = count;
        edges.points.emplace_back(seconds, last);
    }
    const double end = std::max({r.seconds, edges.points.back().first, 1e-3});
    edges.points.emplace_back(end, last);
    c.series.push_back(std::move(edges));
    c.x_max = report::time_ticks(end, c.x_ticks);
    c.y_max = report::linear_ticks(std::max(last, 1.0), c.y_ticks);
    return report::render_chart(c);
}

std::string edges_by_function_table(const CampaignResult& r) {
    std::string t = "<table>\n";
    table_row(t, {"function code of the case that reached them first", "new edges", "share"}, true);
    for (const auto& [fc, edges] : r.edges_by_function)
        table_row(
            t, {xml_escape(codec::function_label(fc)), fmt::format("{}", edges),
                fmt::format("{:.1f}%", r.coverage_edges ? 100.0 * edges / r.coverage_edges : 0.0)});
    t += "</table>\n";
    return t;
}

}  // namespace

std::string format_fuzz_html(const CampaignResult& r, const RunInfo& info) {
    std::string out = report::page_start("mbstorm fuzz report — " + info.target);
    out += fmt::format("<h1>mbstorm fuzz report</h1>\n<p class=\"sub\">{} · seed {} · {}</p>\n",
                       xml_escape(info.target), info.seed,
                       r.coverage ? "coverage-guided" : "black-box");
    out += "<h2>Run</h2>\n" + run_table(r, info);
    out += "<h2>Device model</h2>\n" + model_section(r.model);
    out += fmt::format("<h2>Findings — <span class=\"{}\">{}</span></h2>\n",
                       r.findings.empty() ? "ok" : "bad",
                       r.findings.empty() ? "none" : fmt::format("{}", r.findings.size()));
    out += findings_section(r);
    if (r.coverage) {
        out += "<h2>Coverage</h2>\n" + edges_chart(r);
        out += edges_by_function_table(r);
    }
    return out + report::page_end();
}

}  // namespace mbstorm::netfuzz
