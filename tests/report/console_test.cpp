#include "report/console.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <regex>
#include <string>

#include "report/units.hpp"
#include "sample_result.hpp"

namespace mbstorm::report {
namespace {

bool contains(const std::string& text, const std::string& what) {
    return text.find(what) != std::string::npos;
}

TEST(Units, LatencyHasThreeSignificantDigits) {
    EXPECT_EQ(format_latency(std::uint64_t{850}), "850ns");
    EXPECT_EQ(format_latency(std::uint64_t{1234}), "1.23µs");
    EXPECT_EQ(format_latency(std::uint64_t{812'400}), "812µs");
    EXPECT_EQ(format_latency(std::uint64_t{999'999}), "1.00ms");
    EXPECT_EQ(format_latency(std::uint64_t{12'340'000}), "12.3ms");
    EXPECT_EQ(format_latency(std::uint64_t{2'500'000'000}), "2.50s");
    EXPECT_EQ(format_latency(std::uint64_t{3'600'000'000'000}), "3600s");
}

TEST(Units, CountsRatesBytesDurations) {
    EXPECT_EQ(format_count(0), "0");
    EXPECT_EQ(format_count(100), "100");
    EXPECT_EQ(format_count(1000), "1,000");
    EXPECT_EQ(format_count(1234567), "1,234,567");
    EXPECT_EQ(format_rate(850), "850");
    EXPECT_EQ(format_rate(48'213), "48.2k");
    EXPECT_EQ(format_rate(1'234'000), "1.23M");
    EXPECT_EQ(format_bytes(512), "512 B");
    EXPECT_EQ(format_bytes(1536), "1.50 KiB");
    EXPECT_EQ(format_duration(10'000'000'000), "10.0s");
    EXPECT_EQ(format_duration(125'000'000'000), "2m05s");
    EXPECT_EQ(format_hex_byte(0x0B), "0x0B");
    EXPECT_EQ(format_utc(std::chrono::system_clock::time_point(std::chrono::seconds(1714564800))),
              "2024-05-01T12:00:00Z");
}

TEST(ConsoleReport, ContainsPercentileTableErrorsOperationsStagesThresholds) {
    const auto result = testing::make_sample_result();
    const std::string text = format_console_report(result);
    for (const char* label : {"p50", "p75", "p90", "p99", "p99.9", "p99.99", "p99.999", "max"}) {
        EXPECT_TRUE(contains(text, std::string("\n  ") + label + " ")) << label;
    }
    EXPECT_TRUE(contains(text, "127.0.0.1:15020"));
    EXPECT_TRUE(contains(text, "Throughput"));
    EXPECT_TRUE(contains(text, "tx/s"));
    EXPECT_TRUE(contains(text, "timeout"));
    EXPECT_TRUE(contains(text, "0x02 ILLEGAL DATA ADDRESS"));
    EXPECT_TRUE(contains(text, "Per operation"));
    // Function codes as hex with a prefix and the name; an operation named after its function
    // is not named twice.
    EXPECT_TRUE(contains(text, "  0x03 read_holding_registers "));
    EXPECT_TRUE(contains(text, "  0x06 write_single_register "));
    EXPECT_FALSE(contains(text, "(03)"));
    EXPECT_TRUE(contains(text, "Per stage"));
    EXPECT_TRUE(contains(text, "3. spike"));
    EXPECT_TRUE(contains(text, "FAIL  error_rate < 0.1%"));
    EXPECT_TRUE(contains(text, "engine fell behind: 37 late sends"));
    EXPECT_TRUE(contains(text, "note: embedded slave on 127.0.0.1:15020"));
    // The p99 row shows the histogram's value in its chosen unit.
    EXPECT_TRUE(contains(text, format_latency(result.latency.value_at_percentile(99))));
}

TEST(ConsoleReport, LongOperationNamesAreNotCutAndColumnsStayAligned) {
    auto result = testing::make_sample_result();
    result.operations[0].name = "read_write_multiple_registers_of_the_second_boiler";
    const std::string text = format_console_report(result);
    const std::string label = result.operations[0].name + " (0x" +
                              fmt::format("{:02X}", result.operations[0].function_code) + " " +
                              "read_holding_registers)";
    const auto row = text.find("  " + label + " ");
    ASSERT_NE(row, std::string::npos) << text;
    // The header's "count" column ends where the row's count ends.
    const auto header = text.rfind("\n", text.find("operation (function)")) + 1;
    const auto header_end = text.find('\n', header);
    const auto row_end = text.find('\n', row);
    const std::string header_line = text.substr(header, header_end - header);
    const std::string row_line = text.substr(row, row_end - row);
    // Columns, not bytes: "µs" is two bytes of UTF-8 in one column.
    auto columns = [](const std::string& line) {
        return std::count_if(line.begin(), line.end(), [](char ch) {
            return (static_cast<unsigned char>(ch) & 0xC0) != 0x80;
        });
    };
    EXPECT_EQ(columns(header_line), columns(row_line)) << header_line << "\n" << row_line;
}

TEST(ConsoleReport, OperationsShowTheirFunctionCodeInHexWithItsName) {
    // 0x16 used to print as "mask (16)", next to a --fc that reads 16 as 0x10.
    auto result = testing::make_sample_result();
    result.operations[0].name = "mask";
    result.operations[0].function_code = 0x16;
    result.operations[1].name = "odd";
    result.operations[1].function_code = 0x41;
    const std::string text = format_console_report(result);
    EXPECT_TRUE(contains(text, "  mask (0x16 mask_write_register) ")) << text;
    EXPECT_TRUE(contains(text, "  odd (0x41) ")) << text;
    EXPECT_FALSE(contains(text, "mask (16)")) << text;
    EXPECT_EQ(format_operation("read_coils", 0x01), "0x01 read_coils");
    EXPECT_EQ(format_operation("", 0x10), "0x10 write_multiple_registers");
}

TEST(ConsoleReport, StrayResponsesHaveTheirOwnLineOutsideTheErrors) {
    auto result = testing::make_sample_result();
    const std::uint64_t errors = result.counters.errors();
    result.counters.record(stats::Outcome::UnknownId);
    result.counters.record(stats::Outcome::DuplicateId);
    result.counters.record(stats::Outcome::DuplicateId);
    const std::string text = format_console_report(result);
    EXPECT_TRUE(contains(text,
                         "Stray       3 responses answered no transaction (unknown_id 1, "
                         "duplicate_id 2)"))
        << text;
    EXPECT_TRUE(contains(text, "Errors      " + format_count(errors) + " of ")) << text;
    EXPECT_FALSE(contains(text, "  unknown_id ")) << text;
}

TEST(ConsoleReport, EmptyRunDoesNotPretend) {
    stats::RunResult empty;
    const std::string text = format_console_report(empty);
    EXPECT_TRUE(contains(text, "(no latency samples)"));
    EXPECT_FALSE(contains(text, "Per stage"));
    EXPECT_FALSE(contains(text, "Thresholds"));
}

TEST(Progress, LineShowsRatePercentilesErrorsConnections) {
    stats::IntervalSummary last;
    last.duration_ns = 1'000'000'000;
    last.transactions = 48'200;
    last.p50_ns = 210'000;
    last.p99_ns = 1'200'000;
    last.max_ns = 3'400'000;
    ProgressSample sample{12.0, &last, 500'000, 3, 64};
    const std::string line = format_progress_line(sample);
    EXPECT_TRUE(contains(line, "12.0s")) << line;
    EXPECT_TRUE(std::regex_search(line, std::regex(" 48.2k tx/s"))) << line;
    EXPECT_TRUE(std::regex_search(line, std::regex("p50 +210µs"))) << line;
    EXPECT_TRUE(std::regex_search(line, std::regex("p99 +1.20ms"))) << line;
    EXPECT_TRUE(std::regex_search(line, std::regex("max +3.40ms"))) << line;
    EXPECT_TRUE(contains(line, "errors 3")) << line;
    EXPECT_TRUE(contains(line, "conns 64")) << line;
    EXPECT_EQ(line.find('\n'), std::string::npos);

    sample.last_interval = nullptr;
    EXPECT_TRUE(std::regex_search(format_progress_line(sample), std::regex("p50 +- ")));
}

std::string printed(bool tty) {
    char* buffer = nullptr;
    std::size_t size = 0;
    std::FILE* f = open_memstream(&buffer, &size);
    {
        ProgressPrinter printer(f, tty);
        ProgressSample sample{1.0, nullptr, 0, 0, 1};
        printer.update(sample);
        sample.elapsed_seconds = 2.0;
        printer.update(sample);
        printer.finish();
    }
    std::fclose(f);
    std::string out(buffer, size);
    std::free(buffer);
    return out;
}

TEST(Progress, PrinterRewritesInPlaceOnTtyAndPrintsLinesOtherwise) {
    const std::string tty = printed(true);
    EXPECT_EQ(std::count(tty.begin(), tty.end(), '\r'), 2);
    EXPECT_EQ(std::count(tty.begin(), tty.end(), '\n'), 1);
    EXPECT_EQ(tty.back(), '\n');
    const std::string plain = printed(false);
    EXPECT_EQ(std::count(plain.begin(), plain.end(), '\r'), 0);
    EXPECT_EQ(std::count(plain.begin(), plain.end(), '\n'), 2);
}

// A saturated target used to be reported as the engine falling behind.
TEST(ConsoleReport, LateSendsAreBlamedOnTheEngineOrTheTarget) {
    auto result = testing::make_sample_result();
    result.schedule_lag = {};
    EXPECT_TRUE(contains(format_console_report(result), "Schedule    kept (no late sends)"));
    result.schedule_lag.target = {72'227, 1'570'000'000, 72'227ull * 800'000'000};
    std::string text = format_console_report(result);
    EXPECT_TRUE(contains(text,
                         "Schedule    target not keeping up: 72,227 late sends waited for answers "
                         "(in-flight window full: 16 connections x depth 4), max lag 1.57s"))
        << text;
    EXPECT_FALSE(contains(text, "engine fell behind")) << text;
    result.schedule_lag.engine = {3, 2'000'000, 4'500'000};
    text = format_console_report(result);
    EXPECT_TRUE(contains(text, "Schedule    engine fell behind: 3 late sends (mbstorm's own CPU"))
        << text;
    EXPECT_TRUE(contains(text, "target not keeping up")) << text;
    EXPECT_TRUE(contains(text, "else lower --rate to what it sustained")) << text;
}

// Open loop: the corrected latency (from the intended send) and, beside it, the uncorrected
// service time (from the actual send), as wrk2's --u_latency shows; closed loop: one table.
TEST(ConsoleReport, AnOpenLoopRunShowsTheServiceTimeBesideTheCorrectedLatency) {
    auto result = testing::make_sample_result();
    for (int i = 0; i < 1000; ++i) result.service_time.record(200'000);
    std::string text = format_console_report(result);
    EXPECT_TRUE(contains(text, "samples; from each request's intended send, queueing included)"))
        << text;
    const auto service = text.find(
        "\nService time, uncorrected (1,000 samples; from each "
        "request's actual send");
    ASSERT_NE(service, std::string::npos) << text;
    EXPECT_NE(text.find("200", service), std::string::npos) << text;
    result.metadata.model = stats::LoadModel::Closed;
    text = format_console_report(result);
    EXPECT_FALSE(contains(text, "Service time")) << text;
    EXPECT_FALSE(contains(text, "intended send")) << text;
}

// A ramp 500 -> 2,000/s used to be shown as "rate 2.00k/s", and stages had no target column.
TEST(ConsoleReport, ARampIsShownAsTheScheduleItWas) {
    auto result = testing::make_sample_result();
    const std::string text = format_console_report(result);
    EXPECT_TRUE(contains(text, "depth 4, open loop, stages 500 → 2.00k req/s, duration")) << text;
    const auto header = text.find("  stage ");
    ASSERT_NE(header, std::string::npos) << text;
    EXPECT_NE(text.find("target/s", header), std::string::npos) << text;
    EXPECT_NE(text.find("1. warm"), std::string::npos);
    const auto warm = text.find("1. warm");
    EXPECT_NE(text.substr(warm, text.find('\n', warm) - warm).find("500 → 2.00k"),
              std::string::npos)
        << text;
    const auto steady = text.find("2. steady");
    EXPECT_NE(text.substr(steady, text.find('\n', steady) - steady).find(" 2.00k "),
              std::string::npos)
        << text;
    // A flat run: one rate.
    auto flat = testing::make_sample_result(10, false);
    EXPECT_TRUE(contains(format_console_report(flat), "open loop, 2.00k req/s")) << text;
}

TEST(ConsoleReport, APlanNotCarriedOutIsSaidAndDepthHintsAreGiven) {
    auto result = testing::make_sample_result();
    EXPECT_FALSE(contains(format_console_report(result), "NOT carried out"));
    result.shortfalls.push_back(
        {"connections", 10000, 9326,
         "connections: 9326 of 10000 opened (674 connect attempts failed)"});
    std::string text = format_console_report(result);
    EXPECT_TRUE(contains(text, "Plan        NOT carried out:\n  connections: 9326 of 10000 opened"))
        << text;
    // Timeouts at depth 4: a hedged hint; skipped requests: a firm one.
    EXPECT_TRUE(contains(text, "Hint        ")) << text;
    EXPECT_TRUE(contains(text, "if yours is one, use --depth 1")) << text;
    result.pipelining.skipped_requests = 375;
    text = format_console_report(result);
    EXPECT_TRUE(contains(text,
                         "Hint        375 requests timed out while later ones on the same "
                         "connection were answered"))
        << text;
    result.metadata.depth = 1;
    EXPECT_FALSE(contains(format_console_report(result), "Hint"));
}

}  // namespace
}  // namespace mbstorm::report
