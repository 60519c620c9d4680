#include "report/json.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>

#include "report/interval_json.hpp"
#include "sample_result.hpp"

namespace mbstorm::report {
namespace {

using nlohmann::json;

// Resolves "a.b[].c": "[]" steps into the first array element.
const json* resolve(const json& root, const std::string& path) {
    const json* node = &root;
    std::stringstream parts(path);
    std::string part;
    while (std::getline(parts, part, '.')) {
        bool into_array = false;
        if (part.size() > 2 && part.compare(part.size() - 2, 2, "[]") == 0) {
            part.resize(part.size() - 2);
            into_array = true;
        }
        if (!node->is_object() || !node->contains(part)) return nullptr;
        node = &(*node)[part];
        if (into_array) {
            if (!node->is_array() || node->empty()) return nullptr;
            node = &(*node)[0];
        }
    }
    return node;
}

TEST(Json, EveryDocumentedFieldIsPresent) {
    // A shard of a test started with --start-at: the fields only such runs carry are there too.
    auto r = testing::make_sample_result();
    r.metadata.shard_index = 1;
    r.metadata.shard_count = 3;
    r.metadata.start_at_epoch_s = 1714564800.0;
    r.metadata.late_by_ns = 1'500'000'000;
    const json doc = json::parse(format_json(r));
    std::ifstream schema(MBSTORM_SOURCE_DIR "/docs/json-schema.md");
    ASSERT_TRUE(schema.good());
    const std::regex row(R"(^\| `([^`]+)` \|)");
    std::string line;
    int checked = 0;
    while (std::getline(schema, line)) {
        std::smatch m;
        if (!std::regex_search(line, m, row)) continue;
        EXPECT_NE(resolve(doc, m[1]), nullptr) << "documented but missing: " << m[1];
        ++checked;
    }
    EXPECT_GT(checked, 50);
}

// Open loop: the uncorrected service time beside the corrected latency; closed loop: null.
TEST(Json, AnOpenLoopRunCarriesItsServiceTime) {
    auto r = testing::make_sample_result();
    for (int i = 0; i < 1000; ++i) r.service_time.record(200'000);
    json doc = json::parse(format_json(r));
    ASSERT_TRUE(doc.at("service_time").is_object()) << doc.at("service_time");
    EXPECT_EQ(doc.at("service_time").at("count"), 1000);
    EXPECT_NE(doc.at("service_time").at("mean_ns"), doc.at("latency").at("mean_ns"));
    r.metadata.model = stats::LoadModel::Closed;
    doc = json::parse(format_json(r));
    EXPECT_TRUE(doc.at("service_time").is_null());
}

TEST(Json, ValuesMatchTheRunResult) {
    const auto r = testing::make_sample_result();
    const json doc = json::parse(format_json(r));
    EXPECT_EQ(doc["schema_version"], kJsonSchemaVersion);
    EXPECT_EQ(doc["run"]["target"], "127.0.0.1:15020");
    EXPECT_EQ(doc["run"]["model"], "open");
    EXPECT_EQ(doc["run"]["start_time"], "2024-05-01T12:00:00Z");
    EXPECT_EQ(doc["totals"]["transactions"], r.counters.completed());
    EXPECT_EQ(doc["totals"]["errors"], r.counters.errors());
    EXPECT_EQ(doc["totals"]["stray_responses"], r.counters.stray_responses());
    EXPECT_DOUBLE_EQ(doc["totals"]["throughput_per_s"].get<double>(), r.throughput());
    EXPECT_EQ(doc["latency"]["count"], r.latency.total_count());
    EXPECT_EQ(doc["latency"]["percentiles_ns"]["99.9"], r.latency.value_at_percentile(99.9));
    EXPECT_EQ(doc["latency"]["percentiles_ns"]["100"], r.latency.value_at_percentile(100));
    EXPECT_EQ(doc["latency"]["max_ns"], r.latency.max());
    EXPECT_EQ(doc["outcomes"]["timeout"], r.counters.count(stats::Outcome::Timeout));
    EXPECT_EQ(doc["exceptions"]["0x02"], r.counters.exceptions[0x02]);
    EXPECT_FALSE(doc["exceptions"].contains("0x03"));
    ASSERT_EQ(doc["operations"].size(), 2u);
    EXPECT_EQ(doc["operations"][1]["name"], "write_single_register");
    EXPECT_EQ(doc["operations"][1]["function_code"], 6);
    EXPECT_EQ(doc["operations"][1]["function"], "0x06 write_single_register");
    ASSERT_EQ(doc["stages"].size(), 3u);
    EXPECT_EQ(doc["stages"][2]["name"], "spike");
    EXPECT_EQ(doc["timeline"]["intervals"].size(), r.timeline.size());
    EXPECT_EQ(doc["thresholds_passed"], false);
    EXPECT_EQ(doc["schedule_lag"]["late_sends"], 37);
    EXPECT_EQ(doc["schedule_lag"]["cause"], "engine");
    EXPECT_EQ(doc["schedule_lag"]["engine"]["late_sends"], 37);
    EXPECT_EQ(doc["schedule_lag"]["target"]["late_sends"], 0);
    EXPECT_EQ(doc["run"]["rate_schedule_per_s"], json::array({500.0, 2000.0}));
    EXPECT_EQ(doc["stages"][0]["target_rate_from_per_s"], 500.0);
    EXPECT_EQ(doc["stages"][0]["target_rate_to_per_s"], 2000.0);
    EXPECT_EQ(doc["stages"][2]["target_rate_from_per_s"], 2000.0);
    EXPECT_EQ(doc["stages"][2]["target_connections_to"], 16);
    EXPECT_EQ(doc["plan_carried_out"], true);
    EXPECT_TRUE(doc["plan_shortfalls"].empty());
    // Per-operation traffic is filled (it used to be 0).
    EXPECT_EQ(doc["operations"][0]["totals"]["bytes_sent"], r.operations[0].counters.bytes_sent);
    EXPECT_GT(r.operations[0].counters.bytes_sent, 0u);
}

TEST(Json, ShardAndStartAtOnlyWhenTheRunHadThem) {
    auto r = testing::make_sample_result();
    json doc = json::parse(format_json(r));
    EXPECT_FALSE(doc["test"].contains("shard_index"));
    EXPECT_FALSE(doc["test"].contains("shard_count"));
    EXPECT_FALSE(doc["test"].contains("late_by_seconds"));
    r.metadata.shard_index = 0;
    r.metadata.shard_count = 2;
    r.metadata.start_at_epoch_s = 1714564800.25;
    r.metadata.late_by_ns = 0;
    doc = json::parse(format_json(r));
    EXPECT_EQ(doc["test"]["shard_index"], 0);
    EXPECT_EQ(doc["test"]["shard_count"], 2);
    EXPECT_DOUBLE_EQ(doc["test"]["start_at_epoch_s"].get<double>(), 1714564800.25);
    EXPECT_EQ(doc["test"]["late_by_seconds"], 0.0);
}

TEST(Json, ShortfallsCausesAndHints) {
    auto r = testing::make_sample_result();
    r.schedule_lag.target = {5, 10'000'000, 20'000'000};
    r.shortfalls.push_back({"rate", 8000, 5000, "rate: ..."});
    r.pipelining.skipped_requests = 7;
    const json doc = json::parse(format_json(r));
    EXPECT_EQ(doc["schedule_lag"]["cause"], "engine_and_target");
    EXPECT_EQ(doc["schedule_lag"]["late_sends"], 42);
    EXPECT_EQ(doc["schedule_lag"]["target"]["mean_lag_ns"], 4'000'000.0);
    EXPECT_EQ(doc["plan_carried_out"], false);
    ASSERT_EQ(doc["plan_shortfalls"].size(), 1u);
    EXPECT_EQ(doc["plan_shortfalls"][0]["what"], "rate");
    EXPECT_EQ(doc["plan_shortfalls"][0]["planned"], 8000.0);
    EXPECT_EQ(doc["plan_shortfalls"][0]["achieved"], 5000.0);
    EXPECT_EQ(doc["pipelining"]["skipped_requests"], 7);
    ASSERT_EQ(doc["hints"].size(), 1u);
    EXPECT_NE(doc["hints"][0].get<std::string>().find("--depth 1"), std::string::npos);
}

TEST(Json, EmptyRunAndCompactForm) {
    stats::RunResult empty;
    empty.operations.push_back({"bad \xff name", 3, stats::Histogram(), {}});  // invalid UTF-8
    const std::string text = format_json(empty, -1);
    EXPECT_EQ(text.find('\n'), std::string::npos);
    const json doc = json::parse(text);
    EXPECT_EQ(doc["latency"]["count"], 0);
    EXPECT_TRUE(doc["stages"].is_array());
    EXPECT_TRUE(doc["stages"].empty());
    EXPECT_EQ(doc["thresholds_passed"], true);
}

// The timeline's intervals are written one at a time (a merged 11-day timeline holds a million)
// and spliced into the document: the text must be what dumping the whole tree would print.
TEST(Json, TheTimelineIsPrintedAsTheWholeDocumentWouldBe) {
    auto r = testing::make_sample_result();
    // A name that spells the placeholder's key and value: escaped, so it is not replaced.
    r.operations.front().name = "\"intervals\": \"\x01intervals\x01\"";
    for (std::uint64_t n = 0; n < 3; ++n) {
        stats::IntervalSummary i;
        i.index = 10 + n;
        i.transactions = 1000 * n + 7;
        i.mean_ns = 1234.5 + static_cast<double>(n) / 3.0;
        r.timeline.push_back(i);
    }
    for (const int indent : {-1, 0, 2, 4}) {
        const std::string text = format_json(r, indent);
        const json doc = json::parse(text);
        EXPECT_EQ(text, doc.dump(indent, ' ', false, json::error_handler_t::replace)) << indent;
        ASSERT_EQ(doc["timeline"]["intervals"].size(), r.timeline.size());
        for (std::size_t n = 0; n < r.timeline.size(); ++n)
            EXPECT_EQ(doc["timeline"]["intervals"][n], interval_json(r.timeline[n]));
        EXPECT_EQ(doc["operations"][0]["name"], r.operations.front().name);
    }
    r.timeline.clear();
    const json empty = json::parse(format_json(r));
    EXPECT_TRUE(empty["timeline"]["intervals"].is_array());
    EXPECT_TRUE(empty["timeline"]["intervals"].empty());
}

}  // namespace
}  // namespace mbstorm::report
