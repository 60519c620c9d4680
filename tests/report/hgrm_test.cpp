#include "report/hgrm.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace mbstorm::report {
namespace {

struct HgrmRow {
    double value;
    double percentile;
    std::uint64_t total_count;
    std::string inverse;  // 4th column as text ("inf" on the last row)
};
struct Hgrm {
    std::string header;
    std::vector<HgrmRow> rows;
    double mean = -1, stddev = -1, max = -1;
    std::uint64_t total = 0;
    int buckets = 0, sub_buckets = 0;
};

// A strict reader of the HdrHistogram_c percentile format; fails the test on any deviation.
Hgrm parse_hgrm(const std::string& text) {
    Hgrm out;
    std::istringstream in(text);
    std::string line;
    std::getline(in, out.header);
    std::getline(in, line);
    EXPECT_EQ(line, "") << "blank line after the header";
    while (std::getline(in, line)) {
        if (line.rfind("#[", 0) == 0) {
            double a = 0, b = 0;
            unsigned long long n = 0;
            int i = 0, j = 0;
            if (std::sscanf(line.c_str(), "#[Mean    = %lf, StdDeviation   = %lf]", &a, &b) == 2) {
                out.mean = a;
                out.stddev = b;
            } else if (std::sscanf(line.c_str(), "#[Max     = %lf, Total count    = %llu]", &a,
                                   &n) == 2) {
                out.max = a;
                out.total = n;
            } else if (std::sscanf(line.c_str(), "#[Buckets = %d, SubBuckets     = %d]", &i, &j) ==
                       2) {
                out.buckets = i;
                out.sub_buckets = j;
            } else {
                ADD_FAILURE() << "unexpected footer line: " << line;
            }
            continue;
        }
        EXPECT_TRUE(out.total == 0) << "row after the footer: " << line;
        // Fixed columns: %12.3f %12f %12d %12.2f
        EXPECT_EQ(line.size(), 12u * 4 + 3) << line;
        std::istringstream cols(line);
        HgrmRow row;
        cols >> row.value >> row.percentile >> row.total_count >> row.inverse;
        EXPECT_FALSE(cols.fail()) << line;
        std::string extra;
        EXPECT_FALSE(cols >> extra) << "extra column in: " << line;
        out.rows.push_back(row);
    }
    return out;
}

TEST(Hgrm, MatchesHdrHistogramLayoutExactly) {
    stats::Histogram h;
    for (std::uint64_t v : {1000, 2000, 3000, 4000}) h.record(v);
    // Worked by hand from HdrHistogram's percentile iteration (5 ticks per half distance);
    // 3000 and 4000 sit in 2-ns-wide buckets, so their highest equivalents are 3001 / 4001;
    // 4000 is the max, and no row goes above the max.
    const std::string expected_rows =
        "       Value   Percentile   TotalCount 1/(1-Percentile)\n"
        "\n"
        "       1.000     0.000000            1         1.00\n"
        "       1.000     0.100000            1         1.11\n"
        "       1.000     0.200000            1         1.25\n"
        "       2.000     0.300000            2         1.43\n"
        "       2.000     0.400000            2         1.67\n"
        "       2.000     0.500000            2         2.00\n"
        "       3.001     0.550000            3         2.22\n"
        "       3.001     0.600000            3         2.50\n"
        "       3.001     0.650000            3         2.86\n"
        "       3.001     0.700000            3         3.33\n"
        "       3.001     0.750000            3         4.00\n"
        "       4.000     0.775000            4         4.44\n"
        "       4.000     1.000000            4          inf\n";
    const std::string text = format_hgrm(h, 1e3);
    ASSERT_EQ(text.substr(0, expected_rows.size()), expected_rows);
    EXPECT_NE(text.find("#[Max     =        4.000, Total count    =            4]\n"),
              std::string::npos);
    EXPECT_NE(text.find("#[Buckets =           32, SubBuckets     =         2048]\n"),
              std::string::npos);
}

TEST(Hgrm, ParsesWithMonotonicRowsAndFinalRowAtOne) {
    stats::Histogram h;
    std::mt19937_64 rng(9);
    std::lognormal_distribution<double> dist(std::log(300e3), 0.8);
    for (int i = 0; i < 100000; ++i) h.record(static_cast<std::uint64_t>(dist(rng)));
    const Hgrm g = parse_hgrm(format_hgrm(h));  // default unit: milliseconds

    EXPECT_EQ(g.header, "       Value   Percentile   TotalCount 1/(1-Percentile)");
    ASSERT_GT(g.rows.size(), 50u);
    for (std::size_t i = 1; i < g.rows.size(); ++i) {
        EXPECT_GE(g.rows[i].value, g.rows[i - 1].value);
        EXPECT_GE(g.rows[i].percentile, g.rows[i - 1].percentile);
        EXPECT_GE(g.rows[i].total_count, g.rows[i - 1].total_count);
        EXPECT_LE(g.rows[i].percentile, 1.0);
    }
    EXPECT_EQ(g.rows.front().percentile, 0.0);
    EXPECT_EQ(g.rows.back().percentile, 1.0);
    EXPECT_EQ(g.rows.back().inverse, "inf");
    EXPECT_EQ(g.rows.back().total_count, h.total_count());
    for (std::size_t i = 0; i + 1 < g.rows.size(); ++i) {
        // The percentile column is rounded to 6 decimals, 1/(1-p) amplifies that by 1/(1-p)^2.
        const double expected = 1.0 / (1.0 - g.rows[i].percentile);
        EXPECT_NEAR(std::stod(g.rows[i].inverse), expected, 0.006 + expected * expected * 6e-7);
    }
    EXPECT_NEAR(g.mean, h.mean() / 1e6, 0.0011);
    EXPECT_NEAR(g.stddev, h.stddev() / 1e6, 0.0011);
    EXPECT_NEAR(g.max, static_cast<double>(h.max()) / 1e6, 0.0011);
    EXPECT_LE(g.rows.back().value, g.max);
    EXPECT_EQ(g.total, h.total_count());
    EXPECT_EQ(g.buckets, 32);
    EXPECT_EQ(g.sub_buckets, 2048);
}

TEST(Hgrm, EmptyHistogramHasHeaderAndFooterOnly) {
    const Hgrm g = parse_hgrm(format_hgrm(stats::Histogram()));
    EXPECT_TRUE(g.rows.empty());
    EXPECT_EQ(g.total, 0u);
    EXPECT_EQ(g.max, 0.0);
    EXPECT_EQ(g.sub_buckets, 2048);
}

}  // namespace
}  // namespace mbstorm::report
