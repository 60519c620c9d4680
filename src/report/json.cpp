#include "report/json.hpp"

#include <fmt/format.h>

#include <chrono>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "codec/function_code.hpp"
#include "report/explain.hpp"
#include "report/interval_json.hpp"
#include "report/units.hpp"

namespace mbstorm::report {
namespace {

using nlohmann::json;

// Keys are the percentile as written by humans: "50", "99.9", "99.999", "100".
constexpr std::array<std::pair<double, const char*>, 8> kJsonPercentiles = {{{50.0, "50"},
                                                                             {75.0, "75"},
                                                                             {90.0, "90"},
                                                                             {99.0, "99"},
                                                                             {99.9, "99.9"},
                                                                             {99.99, "99.99"},
                                                                             {99.999, "99.999"},
                                                                             {100.0, "100"}}};

double seconds(std::uint64_t ns) {
    return static_cast<double>(ns) / 1e9;
}

json latency_json(const stats::Histogram& h) {
    json percentiles = json::object();
    for (const auto& [p, key] : kJsonPercentiles) percentiles[key] = h.value_at_percentile(p);
    return {{"count", h.total_count()},
            {"min_ns", h.min()},
            {"max_ns", h.max()},
            {"mean_ns", h.mean()},
            {"stddev_ns", h.stddev()},
            {"saturated", h.saturated_count()},
            {"percentiles_ns", percentiles}};
}

json lag_json(const stats::LagCounts& lag) {
    return {{"late_sends", lag.late_sends},
            {"max_lag_ns", lag.max_lag_ns},
            {"mean_lag_ns", lag.mean_lag_ns()}};
}

json outcomes_json(const stats::OutcomeCounters& c) {
    json outcomes = json::object();
    for (std::size_t i = 0; i < stats::kOutcomeCount; ++i) {
        outcomes[std::string(stats::outcome_name(static_cast<stats::Outcome>(i)))] = c.outcomes[i];
    }
    return outcomes;
}

json exceptions_json(const stats::OutcomeCounters& c) {
    json exceptions = json::object();
    for (std::size_t code = 0; code < c.exceptions.size(); ++code) {
        if (c.exceptions[code] != 0) {
            exceptions[format_hex_byte(static_cast<std::uint8_t>(code))] = c.exceptions[code];
        }
    }
    return exceptions;
}

json totals_json(const stats::OutcomeCounters& c, std::uint64_t duration_ns) {
    const double s = seconds(duration_ns);
    const std::uint64_t completed = c.completed();
    return {{"transactions", completed},
            {"transactions_sent", c.transactions_sent},
            {"ok", c.ok()},
            {"errors", c.errors()},
            {"stray_responses", c.stray_responses()},
            {"error_rate", completed == 0 ? 0.0 : static_cast<double>(c.errors()) / completed},
            {"throughput_per_s", s > 0.0 ? static_cast<double>(completed) / s : 0.0},
            {"bytes_sent", c.bytes_sent},
            {"bytes_received", c.bytes_received}};
}

json operation_json(const stats::OperationResult& op, std::uint64_t duration_ns) {
    return {{"name", op.name},
            {"function_code", op.function_code},
            {"function", codec::function_label(op.function_code)},
            {"totals", totals_json(op.counters, duration_ns)},
            {"latency", latency_json(op.latency)},
            {"outcomes", outcomes_json(op.counters)},
            {"exceptions", exceptions_json(op.counters)}};
}

}  // namespace

json interval_json(const stats::IntervalSummary& i) {
    return {{"index", i.index},
            {"start_offset_s", seconds(i.start_offset_ns)},
            {"transactions", i.transactions},
            {"errors", i.errors},
            {"latency_count", i.latency_count},
            {"throughput_per_s", i.transactions_per_second()},
            {"p50_ns", i.p50_ns},
            {"p90_ns", i.p90_ns},
            {"p99_ns", i.p99_ns},
            {"p99_9_ns", i.p999_ns},
            {"max_ns", i.max_ns},
            {"mean_ns", i.mean_ns},
            {"target_rate_per_s", i.target_rate},
            {"open_connections", i.open_connections}};
}

namespace {

json run_json(const stats::RunResult& r) {
    const auto& m = r.metadata;
    return {{"target", m.target},
            {"threads", m.threads},
            {"backend", m.backend},
            {"connections", m.connections},
            {"depth", m.depth},
            {"model", stats::load_model_name(m.model)},
            {"rate_per_second", m.rate_per_second},
            {"rate_schedule_per_s", rate_schedule(r)},
            {"requested_duration_s", seconds(m.requested_duration_ns)},
            {"measured_duration_s", seconds(m.measured_duration_ns)},
            {"warmup_s", seconds(m.warmup_ns)},
            {"start_time", format_utc(m.start_time)},
            {"coordinated_omission_corrected", m.coordinated_omission_corrected},
            {"notes", m.notes}};
}

json stages_json(const stats::RunResult& r) {
    json stages = json::array();
    for (const auto& st : r.stages) {
        const std::uint64_t span = st.end_offset_ns - st.start_offset_ns;
        json stage_ops = json::array();
        for (const auto& op : st.operations) stage_ops.push_back(operation_json(op, span));
        stages.push_back({{"index", st.index},
                          {"name", st.name},
                          {"start_offset_s", seconds(st.start_offset_ns)},
                          {"end_offset_s", seconds(st.end_offset_ns)},
                          {"target_rate_from_per_s", st.rate_from},
                          {"target_rate_to_per_s", st.rate_to},
                          {"target_connections_from", st.connections_from},
                          {"target_connections_to", st.connections_to},
                          {"totals", totals_json(st.counters, span)},
                          {"latency", latency_json(st.latency)},
                          {"outcomes", outcomes_json(st.counters)},
                          {"exceptions", exceptions_json(st.counters)},
                          {"operations", stage_ops}});
    }
    return stages;
}

json thresholds_json(const stats::RunResult& r) {
    json thresholds = json::array();
    for (const auto& t : r.thresholds) {
        thresholds.push_back({{"expression", t.expression},
                              {"observed", t.observed},
                              {"observed_text", t.observed_text},
                              {"passed", t.passed}});
    }
    return thresholds;
}

json shortfalls_json(const stats::RunResult& r) {
    json shortfalls = json::array();
    for (const auto& s : r.shortfalls) {
        shortfalls.push_back(
            {{"what", s.what}, {"planned", s.planned}, {"achieved", s.achieved}, {"text", s.text}});
    }
    return shortfalls;
}

// The test this run belongs to: what `mbstorm merge` reads to put runs together.
json test_json(const stats::RunResult& r) {
    const auto& m = r.metadata;
    const double measure_start =
        m.start_time.time_since_epoch().count() == 0
            ? 0.0
            : std::chrono::duration<double>(m.start_time.time_since_epoch()).count() +
                  seconds(m.warmup_ns);
    const stats::Histogram& h = r.latency;
    json test = {{"id", m.test_id},
                 {"run_id", m.run_id},
                 {"merged_runs", m.merged_runs},
                 {"measure_start_epoch_s", measure_start},
                 {"histogram",
                  {{"lowest_discernible_ns", 1},
                   {"highest_trackable_ns", h.highest_trackable()},
                   {"significant_digits", stats::Histogram::kSignificantDigits}}}};
    // run --shard I/N: which part of the test this is (mbstorm merge wants each exactly once).
    if (m.shard_count != 0) {
        test["shard_index"] = m.shard_index;
        test["shard_count"] = m.shard_count;
    }
    // run --start-at: the start asked for and how late the run began against it.
    if (m.start_at_epoch_s != 0.0) {
        test["start_at_epoch_s"] = m.start_at_epoch_s;
        test["late_by_seconds"] = seconds(m.late_by_ns);
    }
    return test;
}

json connections_json(const stats::ConnectionStats& c) {
    return {{"opened", c.opened},
            {"failed", c.failed},
            {"reconnects", c.reconnects},
            {"closed_by_peer", c.closed_by_peer},
            {"peak_open", c.peak_open},
            {"tls_handshakes", c.tls_handshakes},
            {"tls_resumed", c.tls_resumed},
            {"tls_handshake_ns_total", c.tls_handshake_ns_total},
            {"tls_handshake_ns_max", c.tls_handshake_ns_max},
            {"tls_handshake_failures", c.tls_handshake_failures},
            {"tls_offloaded", c.tls_offloaded},
            {"tls_offload_errors", c.tls_offload_errors},
            {"failed_by_cause", c.failed_by_cause}};
}

json schedule_lag_json(const stats::RunResult& r) {
    const auto& lag = r.schedule_lag;
    const stats::LagCounts all_lag = lag.total();
    return {{"late_sends", all_lag.late_sends},     {"max_lag_ns", all_lag.max_lag_ns},
            {"mean_lag_ns", all_lag.mean_lag_ns()}, {"cause", schedule_lag_cause(lag)},
            {"engine", lag_json(lag.engine)},       {"target", lag_json(lag.target)}};
}

}  // namespace

namespace {

// Stands in the document for the timeline's intervals until they are written as text.
constexpr std::string_view kIntervalsPlaceholder = "\x01intervals\x01";

// Appends the intervals as the document's dump would print them at nesting `depth`, made one
// at a time: as a tree an interval takes some 4 KB, as text about 450 bytes, and a merged
// timeline may hold a million (an 11-day test).
// `then`: bytes that will follow, reserved with the rest.
void append_intervals(std::string& text, const std::vector<stats::IntervalSummary>& timeline,
                      int indent, int depth, std::size_t then) {
    if (timeline.empty()) {
        text += "[]";
        return;
    }
    const bool pretty = indent >= 0;
    const std::string outer(pretty ? static_cast<std::size_t>(indent * depth) : 0, ' ');
    const std::string inner(pretty ? static_cast<std::size_t>(indent * (depth + 1)) : 0, ' ');
    text += pretty ? "[\n" : "[";
    const std::size_t start = text.size();
    for (std::size_t n = 0; n < timeline.size(); ++n) {
        if (n != 0) text += pretty ? ",\n" : ",";
        text += inner;
        // Numbers only, so every new line in the dump is one of its own lines: indent it.
        for (const char c : interval_json(timeline[n]).dump(indent)) {
            text += c;
            if (c == '\n') text += inner;
        }
        // Room for the rest at the first one's size and a little more (numbers vary in
        // length), so that the text is not copied as it grows.
        if (n == 0) {
            const std::size_t each = text.size() - start + 2;
            text.reserve(text.size() + each * timeline.size() * 9 / 8 + outer.size() + then + 8);
        }
    }
    text += pretty ? "\n" + outer + "]" : "]";
}

// Puts the intervals where the placeholder was dumped (the value of "intervals": only a key
// is followed by an unescaped quote, so a user's string cannot look like it).
std::string splice_intervals(const std::string& text, const stats::RunResult& r, int indent) {
    const std::string key = json(std::string(kIntervalsPlaceholder)).dump();
    const std::string needle = (indent >= 0 ? "\"intervals\": " : "\"intervals\":") + key;
    const std::size_t at = text.find(needle);
    if (at == std::string::npos) return text;
    const std::size_t value = at + needle.size() - key.size();
    std::string out = text.substr(0, value);
    append_intervals(out, r.timeline, indent, 2, text.size() - value - key.size());
    out.append(text, value + key.size());
    return out;
}

}  // namespace

std::string format_json(const stats::RunResult& r, int indent) {
    const auto& m = r.metadata;
    json operations = json::array();
    for (const auto& op : r.operations)
        operations.push_back(operation_json(op, m.measured_duration_ns));
    const json intervals = std::string(kIntervalsPlaceholder);
    json doc = {
        {"schema_version", kJsonSchemaVersion},
        {"tool", m.tool_version},
        {"run", run_json(r)},
        {"test", test_json(r)},
        {"totals", totals_json(r.counters, m.measured_duration_ns)},
        {"latency", latency_json(r.latency)},
        {"service_time",
         r.metadata.model == stats::LoadModel::Open && r.service_time.total_count() != 0
             ? latency_json(r.service_time)
             : json(nullptr)},
        {"outcomes", outcomes_json(r.counters)},
        {"exceptions", exceptions_json(r.counters)},
        {"operations", operations},
        {"stages", stages_json(r)},
        {"timeline", {{"interval_s", seconds(r.timeline_interval_ns)}, {"intervals", intervals}}},
        {"schedule_lag", schedule_lag_json(r)},
        {"connections", connections_json(r.connections)},
        {"plan_carried_out", r.shortfalls.empty()},
        {"plan_shortfalls", shortfalls_json(r)},
        {"pipelining", {{"skipped_requests", r.pipelining.skipped_requests}}},
        {"hints", hint_lines(r)},
        {"thresholds", thresholds_json(r)},
        {"thresholds_passed", r.thresholds_passed()}};
    // Replace invalid UTF-8 in user-supplied names instead of throwing.
    return splice_intervals(doc.dump(indent, ' ', false, json::error_handler_t::replace), r,
                            indent);
}

}  // namespace mbstorm::report
