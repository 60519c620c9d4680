#include "report/html.hpp"

#include <gtest/gtest.h>

#include <regex>
#include <string>

#include "sample_result.hpp"

namespace mbstorm::report {
namespace {

std::size_t count(const std::string& text, const std::string& what) {
    std::size_t n = 0;
    for (auto pos = text.find(what); pos != std::string::npos; pos = text.find(what, pos + 1)) ++n;
    return n;
}

void expect_well_formed(const std::string& html) {
    EXPECT_EQ(html.rfind("<!DOCTYPE html>", 0), 0u);
    EXPECT_NE(html.find("</html>"), std::string::npos);
    EXPECT_EQ(count(html, "<svg "), count(html, "</svg>"));
    EXPECT_EQ(count(html, "<g "), count(html, "</g>"));
    EXPECT_EQ(count(html, "<text "), count(html, "</text>"));
    EXPECT_EQ(count(html, "<polyline "), count(html, "</polyline>"));
    EXPECT_EQ(count(html, "<table"), count(html, "</table>"));
    EXPECT_EQ(count(html, "<tr>"), count(html, "</tr>"));
    // Childless SVG elements are self-closed.
    for (const char* tag : {"<line ", "<rect "}) {
        for (auto pos = html.find(tag); pos != std::string::npos; pos = html.find(tag, pos + 1)) {
            const auto end = html.find('>', pos);
            ASSERT_NE(end, std::string::npos);
            EXPECT_EQ(html[end - 1], '/') << html.substr(pos, end - pos + 1);
        }
    }
    // Self-contained: no scripts, no external resources; the only URL is the SVG namespace.
    EXPECT_EQ(html.find("<script"), std::string::npos);
    EXPECT_EQ(html.find(" src="), std::string::npos);
    EXPECT_EQ(html.find("<link"), std::string::npos);
    EXPECT_EQ(html.find("url("), std::string::npos);
    EXPECT_EQ(count(html, "http"), count(html, "xmlns=\"http://www.w3.org/2000/svg\""));
}

TEST(Html, SampleReportIsSelfContainedAndWellFormed) {
    const std::string html = format_html(testing::make_sample_result());
    expect_well_formed(html);
    // Percentile, throughput, latency over time, and (staged) open connections.
    EXPECT_EQ(count(html, "<svg "), 4u);
    for (const char* label : {">0%<", ">90%<", ">99%<", ">99.9%<", ">99.99%<"}) {
        EXPECT_NE(html.find(label), std::string::npos) << label;
    }
    // One line per operation plus overall in the percentile plot; throughput, errors and the
    // open-loop target rate; p50, p99 and max; open connections.
    EXPECT_EQ(count(html, "<polyline "), 3u + 3u + 3u + 1u);
    EXPECT_NE(html.find("target rate"), std::string::npos);
    EXPECT_NE(html.find("Open connections over time"), std::string::npos);
    // Stage boundaries are marked on the three time plots.
    EXPECT_EQ(count(html, "class=\"marker\""), 9u);
    EXPECT_NE(html.find(">spike</text>"), std::string::npos);
    // User text is escaped.
    EXPECT_NE(html.find("synthetic data &lt;for tests&gt; &amp; demos"), std::string::npos);
    EXPECT_NE(html.find("exception 0x02"), std::string::npos);
    EXPECT_NE(html.find("p99.999"), std::string::npos);
    EXPECT_NE(html.find("FAIL"), std::string::npos);
}

TEST(Html, WithoutStagesThereAreNoMarkers) {
    const std::string html = format_html(testing::make_sample_result(10, false));
    expect_well_formed(html);
    EXPECT_EQ(count(html, "class=\"marker\""), 0u);
    EXPECT_EQ(html.find("<h2>Stages"), std::string::npos);
    EXPECT_EQ(html.find("Open connections over time"), std::string::npos);
}

TEST(Html, StrayResponsesAreShownApartFromTransactions) {
    auto result = testing::make_sample_result();
    result.counters.record(stats::Outcome::DuplicateId);
    const std::string html = format_html(result);
    EXPECT_NE(html.find("Stray responses"), std::string::npos);
    EXPECT_NE(html.find("duplicate_id (stray response)"), std::string::npos);
}

// A 3.002 s run used to be drawn on axes running to 4 s.
TEST(Html, TimeAxesEndAtTheRunsLength) {
    auto result = testing::make_sample_result(3, false);
    result.metadata.measured_duration_ns = 3'002'000'000;
    const std::string html = format_html(result);
    expect_well_formed(html);
    EXPECT_EQ(count(html, "class=\"xlab\">3</text>"), 2u);  // throughput and latency over time
    EXPECT_EQ(html.find("class=\"xlab\">4</text>"), std::string::npos);
}

// The schedule as it was: the ramp in the run table, each stage's target rate in its row; why
// sends were late; what the plan did not get; what to change.
TEST(Html, ScheduleCausesShortfallsAndHints) {
    auto result = testing::make_sample_result();
    result.schedule_lag.target = {12, 1'570'000'000, 12 * 900'000'000ull};
    result.shortfalls.push_back({"connections", 16, 9, "connections: 9 of 16 opened"});
    result.pipelining.skipped_requests = 5;
    const std::string html = format_html(result);
    expect_well_formed(html);
    EXPECT_NE(html.find("open loop, stages 500 → 2.00k req/s"), std::string::npos);
    EXPECT_NE(html.find("<th>target/s</th>"), std::string::npos);
    EXPECT_NE(html.find("<td>500 → 2.00k</td>"), std::string::npos);
    EXPECT_NE(html.find("target not keeping up: 12 late sends"), std::string::npos);
    EXPECT_NE(html.find("engine fell behind: 37 late sends"), std::string::npos);
    EXPECT_NE(html.find("NOT carried out</span>: connections: 9 of 16 opened"), std::string::npos);
    EXPECT_NE(html.find("use --depth 1"), std::string::npos);
}

TEST(Html, EmptyRunStillRenders) {
    const std::string html = format_html(stats::RunResult{});
    expect_well_formed(html);
    EXPECT_EQ(count(html, "<svg "), 1u);  // empty percentile plot, no timeline
    EXPECT_NE(html.find("No errors."), std::string::npos);
}

}  // namespace
}  // namespace mbstorm::report
