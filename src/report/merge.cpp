#include "report/merge.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include "report/units.hpp"

namespace mbstorm::report {
namespace {

using nlohmann::json;

// A count, an id or a time in ns as a shard wrote it: a whole number that fits `T`. Anything
// else (a fraction, a sign, 3e26) refuses the file with what was wrong, rather than being
// converted out of range (undefined behaviour; found by fuzz_merge_json).
template <class T>
T whole(const json& v) {
    if (v.is_number_unsigned()) {
        const auto u = v.get<std::uint64_t>();
        if (u <= static_cast<std::uint64_t>(std::numeric_limits<T>::max()))
            return static_cast<T>(u);
    } else if (v.is_number_integer()) {
        const auto i = v.get<std::int64_t>();
        if (std::numeric_limits<T>::is_signed &&
            i >= static_cast<std::int64_t>(std::numeric_limits<T>::min()) &&
            i <= static_cast<std::int64_t>(std::numeric_limits<T>::max()))
            return static_cast<T>(i);
    }
    throw std::runtime_error(fmt::format("{} is not a whole number from {} to {}", v.dump(),
                                         +std::numeric_limits<T>::min(),
                                         +std::numeric_limits<T>::max()));
}

// The count `name` of `j`, 0 when it is absent.
std::uint64_t whole_or(const json& j, const char* name) {
    const auto it = j.find(name);
    return it == j.end() ? 0 : whole<std::uint64_t>(*it);
}

// Saturates rather than converting out of range (a mean lag times a count may be anything).
std::uint64_t ns_from_s(double s) {
    if (!(s > 0.0)) return 0;
    const double ns = std::round(s * 1e9);
    return ns >= 1.8e19 ? UINT64_MAX : static_cast<std::uint64_t>(ns);
}

// Bounds on what a run's JSON may say, so that no edited number makes the merge allocate
// without bound (a timeline slot per interval of a year-long span, 2e9 shards to list) or
// convert out of range (1e300 s in ns).
constexpr double kMaxRunSeconds = 1e8;     // about three years: any soak, in ns easily
constexpr double kMaxEpochSeconds = 1e10;  // the year 2286
constexpr double kMaxRatePerSecond = 1e12;
constexpr double kMinIntervalSeconds = 1e-3;  // run's timeline intervals are 1 ms or longer
constexpr int kMaxShards = 100'000;           // as run --shard allows

// The number `name` of `j`, finite and within [lo, hi], else the file is refused naming it.
double number_within(const json& j, const char* name, double lo, double hi) {
    const json& v = j.at(name);
    const double x = v.is_number() ? v.get<double>() : std::nan("");
    if (!(x >= lo && x <= hi))
        throw std::runtime_error(
            fmt::format("{} is {}: not a number from {} to {}", name, v.dump(), lo, hi));
    return x;
}

std::uint64_t ns_within(const json& j, const char* name, double lo_s = 0.0,
                        double hi_s = kMaxRunSeconds) {
    return ns_from_s(number_within(j, name, lo_s, hi_s));
}

void read_counters(const json& outcomes, const json& exceptions, const json& totals,
                   stats::OutcomeCounters& c) {
    for (std::size_t i = 0; i < stats::kOutcomeCount; ++i) {
        const std::string name(stats::outcome_name(static_cast<stats::Outcome>(i)));
        c.outcomes[i] = whole_or(outcomes, name.c_str());
    }
    for (const auto& [key, count] : exceptions.items()) {
        const unsigned long code = std::stoul(key, nullptr, 16);
        if (code < c.exceptions.size()) c.exceptions[code] = whole<std::uint64_t>(count);
    }
    c.transactions_sent = whole_or(totals, "transactions_sent");
    c.bytes_sent = whole_or(totals, "bytes_sent");
    c.bytes_received = whole_or(totals, "bytes_received");
}

void read_lag(const json& j, stats::LagCounts& lag) {
    lag.late_sends = whole_or(j, "late_sends");
    lag.max_lag_ns = whole_or(j, "max_lag_ns");
    lag.total_lag_ns =
        ns_from_s(j.value("mean_lag_ns", 0.0) * static_cast<double>(lag.late_sends) / 1e9);
}

// The run id of the log's first line; empty when it has none.
std::string log_run_id(const Hlog& log) {
    HlogIdentity id;
    return find_hlog_identity(log, id) ? id.run_id : std::string();
}

std::string shard_text(int index, int count) {
    return count > 0 ? fmt::format("shard {}/{}", index, count) : std::string("not a shard");
}

// What must agree for runs to be parts of one test (see merge.hpp).
std::string plan_of(const ShardRun& s) {
    const auto& m = s.summary.metadata;
    std::string ops;
    for (const auto& op : s.summary.operations)
        ops += fmt::format("{}{} (0x{:02X})", ops.empty() ? "" : ", ", op.name, op.function_code);
    return fmt::format(
        "target {}, {} loop, operations [{}], duration {:.3f}s, warm-up {:.3f}s, "
        "interval {:.3f}s",
        m.target, stats::load_model_name(m.model), ops,
        static_cast<double>(m.requested_duration_ns) / 1e9, static_cast<double>(m.warmup_ns) / 1e9,
        static_cast<double>(s.summary.timeline_interval_ns) / 1e9);
}

std::string name_of(const ShardRun& s) {
    return fmt::format("{} (run {})", s.json_path, s.summary.metadata.run_id);
}

// Runs of one distributed test run at the same time; merged when they did not, the duration
// spans them all and the throughput divides by time some of them were not running. Empty
// when some instant had every run going and no stretch had none.
std::string overlap_warning(const std::vector<ShardRun>& shards) {
    struct Span {
        double start, end;
    };
    std::vector<Span> spans;
    for (const auto& s : shards)
        spans.push_back({s.measure_start_epoch_s,
                         s.measure_start_epoch_s +
                             static_cast<double>(s.summary.metadata.measured_duration_ns) / 1e9});
    std::sort(spans.begin(), spans.end(), [](Span a, Span b) { return a.start < b.start; });
    double latest_start = spans.front().start, earliest_end = spans.front().end, idle = 0;
    double covered_to = spans.front().end, last_end = spans.front().end;
    for (const Span& sp : spans) {
        latest_start = std::max(latest_start, sp.start);
        earliest_end = std::min(earliest_end, sp.end);
        idle += std::max(0.0, sp.start - covered_to);
        covered_to = std::max(covered_to, sp.end);
        last_end = std::max(last_end, sp.end);
    }
    if (latest_start < earliest_end && idle < 1e-3) return {};
    return fmt::format(
        "the runs did not all run at the same time: {:.1f} s from the first start to the last "
        "end, {:.1f} s with every run going, {:.1f} s with none; the duration and throughput "
        "count that whole span (start the runs of one test together: run --start-at)",
        last_end - spans.front().start, std::max(0.0, earliest_end - latest_start), idle);
}

// A merged interval's counts, from the runs' JSONs. Its latencies are reduced to their summary
// as soon as every run's histogram of that interval has been added (see LatencySlots): a
// histogram per interval of an 8-hour test would take 7.8 GB.
struct SlotCounts {
    std::uint64_t transactions = 0, errors = 0;
    double target_rate = 0.0;
    std::uint32_t open_connections = 0;
};

// The longest merged timeline: 11.5 days of 1 s intervals, some 120 MB of summaries. Past it
// the runs are refused (runs of one test days apart, an edited start time) rather than
// allocated for.
constexpr double kMaxTimelineSlots = 1'000'000;
// How far outside its run's own span a log line may start (the last interval runs past the
// measured end; a run's first answers can land in the interval before its start).
constexpr double kLineAllowanceSeconds = 1.0;
// Logs kept open at once while their untagged lines are read again in time order; past it
// each is reopened per line (a file descriptor per run of a 1000-shard test is too many).
constexpr std::size_t kMaxOpenLogs = 64;

// A run's interval lines: streamed from its log file (read_shards), one decoded histogram at
// a time, or from memory (ShardRun::log.intervals, as tests build runs).
class IntervalLines {
  public:
    explicit IntervalLines(const ShardRun& run) : run_(&run) {}

    // use(line, position) for every line in the log's order, until use returns false.
    // False with error on a bad line or when use said stop (error then its own).
    template <class Use>
    bool each(Use&& use, HlogInterval& scratch, std::string& error) {
        if (!run_->log_from_file) {
            for (std::size_t i = 0; i < run_->log.intervals.size(); ++i)
                if (!use(run_->log.intervals[i], i)) return false;
            return true;
        }
        if (!open(error)) return false;
        bool stopped = false;
        while (!stopped && reader_->next(scratch)) stopped = !use(scratch, reader_->line_offset());
        if (!stopped && !reader_->error().ok())
            error = fmt::format("{}: {}", run_->hlog_path, reader_->error().text());
        const bool read = !stopped && reader_->error().ok();
        close();  // reopened by at(): a test of 1000 shards may not hold 1000 files open
        return read;
    }
    // The line at a position each() gave (decoded into scratch when read from the file).
    const HlogInterval* at(std::uint64_t position, HlogInterval& scratch, std::string& error) {
        if (!run_->log_from_file) return &run_->log.intervals[position];
        if (!reader_ && !open(error)) return nullptr;
        if (reader_->read_at(position, scratch)) return &scratch;
        error = fmt::format("{}: changed while being merged ({})", run_->hlog_path,
                            reader_->error().ok() ? "a line is gone" : reader_->error().text());
        return nullptr;
    }
    void close() {
        reader_.reset();
        file_.reset();
    }

  private:
    bool open(std::string& error) {
        file_ = std::make_unique<std::ifstream>(run_->hlog_path, std::ios::binary);
        if (!*file_) {
            error = fmt::format("{}: cannot open", run_->hlog_path);
            return false;
        }
        reader_ = std::make_unique<HlogReader>(*file_);
        return true;
    }

    const ShardRun* run_;
    std::unique_ptr<std::ifstream> file_;
    std::unique_ptr<HlogReader> reader_;
};

// An untagged (all operations) line of a run's log and the merged interval it falls in.
struct SlotLine {
    std::int64_t slot;
    std::uint32_t run;
    std::uint64_t position;  // IntervalLines::at()
};

// The runs' untagged lines, added interval by interval in time order into one histogram
// that is reduced to the interval's summary before the next: memory is two histograms
// (this and a decoded line) however long the test. Each line is also added into `total`
// and counted in `logged` (per run). Summaries only for intervals some line falls in.
bool summarize_latency_slots(std::vector<SlotLine>& lines, std::vector<IntervalLines>& runs,
                             std::uint64_t interval_ns, stats::Histogram& total,
                             std::vector<std::uint64_t>& logged,
                             std::map<std::int64_t, stats::IntervalSummary>& out,
                             std::string& error) {
    std::sort(lines.begin(), lines.end(), [](const SlotLine& a, const SlotLine& b) {
        return std::tie(a.slot, a.run, a.position) < std::tie(b.slot, b.run, b.position);
    });
    const bool keep_open = runs.size() <= kMaxOpenLogs;
    stats::Histogram slot_latency;
    HlogInterval scratch;
    for (std::size_t i = 0; i < lines.size();) {
        const std::int64_t slot = lines[i].slot;
        slot_latency.reset();
        for (; i < lines.size() && lines[i].slot == slot; ++i) {
            IntervalLines& run = runs[lines[i].run];
            const HlogInterval* line = run.at(lines[i].position, scratch, error);
            if (line == nullptr) return false;
            slot_latency.add(line->histogram);
            total.add(line->histogram);
            logged[lines[i].run] += line->histogram.total_count();
            if (!keep_open) run.close();
        }
        out.emplace(slot, stats::summarize_interval(0, interval_ns, slot_latency, 0, 0));
    }
    for (auto& run : runs) run.close();
    return true;
}

// Merged interval k: its counts (if any run's JSON has the interval) and its latency summary
// (if any run's log does); an interval with neither is a gap, empty, with no histogram.
stats::IntervalSummary merged_interval(
    std::int64_t k, std::uint64_t interval_ns, const std::map<std::int64_t, SlotCounts>& counts,
    const std::map<std::int64_t, stats::IntervalSummary>& latency) {
    stats::IntervalSummary s;
    if (const auto it = latency.find(k); it != latency.end()) s = it->second;
    s.index = static_cast<std::uint64_t>(k);
    s.start_offset_ns = s.index * interval_ns;
    s.duration_ns = interval_ns;
    if (const auto it = counts.find(k); it != counts.end()) {
        s.transactions = it->second.transactions;
        s.errors = it->second.errors;
        s.target_rate = it->second.target_rate;
        s.open_connections = it->second.open_connections;
    }
    return s;
}

}  // namespace

namespace {

// The JSON summary's parts, each throwing what is wrong (read_shard_summary names the file).
void read_test_object(const json& doc, ShardRun& out) {
    if (!doc.contains("test"))
        throw std::runtime_error(
            "no 'test' object: written by an mbstorm without --hlog support; run it again");
    const json& t = doc.at("test");
    auto& m = out.summary.metadata;
    m.test_id = t.at("id").get<std::string>();
    m.run_id = t.at("run_id").get<std::string>();
    m.merged_runs = whole<std::uint32_t>(t.at("merged_runs"));
    if (m.merged_runs != 0)
        throw std::runtime_error(fmt::format(
            "it is a merged result ({} runs): merge the runs' own files", m.merged_runs));
    out.measure_start_epoch_s = number_within(t, "measure_start_epoch_s", 0, kMaxEpochSeconds);
    out.shard_index = t.contains("shard_index") ? whole<int>(t.at("shard_index")) : -1;
    out.shard_count = t.contains("shard_count") ? whole<int>(t.at("shard_count")) : 0;
    if (out.shard_count < 0 || out.shard_count > kMaxShards)
        throw std::runtime_error(
            fmt::format("shard_count {} is not one run --shard makes (0, or 1 to {})",
                        out.shard_count, kMaxShards));
    const json& h = t.at("histogram");
    out.lowest_discernible_ns = whole<std::uint64_t>(h.at("lowest_discernible_ns"));
    out.highest_trackable_ns = whole<std::uint64_t>(h.at("highest_trackable_ns"));
    out.significant_digits = whole<int>(h.at("significant_digits"));
}

void read_run_object(const json& doc, ShardRun& out) {
    auto& m = out.summary.metadata;
    const json& r = doc.at("run");
    m.tool_version = doc.value("tool", "mbstorm");
    m.target = r.at("target").get<std::string>();
    m.threads = whole<std::uint32_t>(r.at("threads"));
    m.backend = r.value("backend", std::string());
    m.connections = whole<std::uint32_t>(r.at("connections"));
    m.depth = whole<std::uint32_t>(r.at("depth"));
    m.model = r.at("model").get<std::string>() == "open" ? stats::LoadModel::Open
                                                         : stats::LoadModel::Closed;
    m.rate_per_second = number_within(r, "rate_per_second", 0, kMaxRatePerSecond);
    m.requested_duration_ns = ns_within(r, "requested_duration_s");
    m.measured_duration_ns = ns_within(r, "measured_duration_s");
    m.warmup_ns = ns_within(r, "warmup_s");
    m.coordinated_omission_corrected = r.at("coordinated_omission_corrected").get<bool>();
    m.notes = r.at("notes").get<std::vector<std::string>>();
}

void read_counts_and_operations(const json& doc, ShardRun& out) {
    read_counters(doc.at("outcomes"), doc.at("exceptions"), doc.at("totals"), out.summary.counters);
    const json& lat = doc.at("latency");
    out.latency_count = whole<std::uint64_t>(lat.at("count"));
    out.min_ns = whole<std::uint64_t>(lat.at("min_ns"));
    out.max_ns = whole<std::uint64_t>(lat.at("max_ns"));
    for (const json& op : doc.at("operations")) {
        stats::OperationResult o;
        o.name = op.at("name").get<std::string>();
        o.function_code = whole<std::uint8_t>(op.at("function_code"));
        read_counters(op.at("outcomes"), op.at("exceptions"), op.at("totals"), o.counters);
        out.op_min_ns.push_back(whole<std::uint64_t>(op.at("latency").at("min_ns")));
        out.op_max_ns.push_back(whole<std::uint64_t>(op.at("latency").at("max_ns")));
        out.summary.operations.push_back(std::move(o));
    }
}

void read_timeline(const json& doc, ShardRun& out) {
    const json& tl = doc.at("timeline");
    out.summary.timeline_interval_ns = ns_within(tl, "interval_s", kMinIntervalSeconds);
    for (const json& iv : tl.at("intervals")) {
        stats::IntervalSummary s;
        s.index = whole<std::uint64_t>(iv.at("index"));
        s.start_offset_ns = ns_within(iv, "start_offset_s");
        s.transactions = whole<std::uint64_t>(iv.at("transactions"));
        s.errors = whole<std::uint64_t>(iv.at("errors"));
        s.target_rate = number_within(iv, "target_rate_per_s", 0, kMaxRatePerSecond);
        s.open_connections = whole<std::uint32_t>(iv.at("open_connections"));
        out.summary.timeline.push_back(s);
    }
}

void read_connections(const json& doc, ShardRun& out) {
    const json& lag = doc.at("schedule_lag");
    read_lag(lag.at("engine"), out.summary.schedule_lag.engine);
    read_lag(lag.at("target"), out.summary.schedule_lag.target);
    const json& c = doc.at("connections");
    auto& cs = out.summary.connections;
    cs.opened = whole<std::uint64_t>(c.at("opened"));
    cs.failed = whole<std::uint64_t>(c.at("failed"));
    cs.reconnects = whole<std::uint64_t>(c.at("reconnects"));
    cs.closed_by_peer = whole<std::uint64_t>(c.at("closed_by_peer"));
    cs.peak_open = whole<std::uint64_t>(c.at("peak_open"));
    // TLS counters (written by every run; absent from reports older than them: 0).
    cs.tls_handshakes = whole_or(c, "tls_handshakes");
    cs.tls_resumed = whole_or(c, "tls_resumed");
    cs.tls_handshake_ns_total = whole_or(c, "tls_handshake_ns_total");
    cs.tls_handshake_ns_max = whole_or(c, "tls_handshake_ns_max");
    cs.tls_handshake_failures = whole_or(c, "tls_handshake_failures");
    cs.tls_offloaded = whole_or(c, "tls_offloaded");
    if (const auto causes = c.find("failed_by_cause"); causes != c.end())
        for (const auto& [name, count] : causes->items())
            cs.failed_by_cause[name] = whole<std::uint64_t>(count);
    cs.tls_offload_errors = whole_or(c, "tls_offload_errors");
}

void read_shortfalls_and_thresholds(const json& doc, ShardRun& out) {
    for (const json& s : doc.at("plan_shortfalls")) {
        stats::PlanShortfall p;
        p.what = s.at("what").get<std::string>();
        p.planned = s.at("planned").get<double>();
        p.achieved = s.at("achieved").get<double>();
        p.text = s.at("text").get<std::string>();
        out.summary.shortfalls.push_back(std::move(p));
    }
    out.summary.pipelining.skipped_requests =
        whole<std::uint64_t>(doc.at("pipelining").at("skipped_requests"));
    for (const json& th : doc.at("thresholds")) {
        std::string e = th.at("expression").get<std::string>();
        if (e != "plan carried out") out.threshold_expressions.push_back(std::move(e));
    }
}

void read_stages(const json& doc, ShardRun& out) {
    for (const json& st : doc.at("stages")) {
        stats::StageResult stage;
        stage.index = whole<std::uint32_t>(st.at("index"));
        stage.name = st.at("name").get<std::string>();
        stage.start_offset_ns = ns_within(st, "start_offset_s");
        stage.end_offset_ns = ns_within(st, "end_offset_s");
        stage.rate_from = number_within(st, "target_rate_from_per_s", 0, kMaxRatePerSecond);
        stage.rate_to = number_within(st, "target_rate_to_per_s", 0, kMaxRatePerSecond);
        stage.connections_from = whole<std::uint32_t>(st.at("target_connections_from"));
        stage.connections_to = whole<std::uint32_t>(st.at("target_connections_to"));
        read_counters(st.at("outcomes"), st.at("exceptions"), st.at("totals"), stage.counters);
        out.stage_min_ns.push_back(whole<std::uint64_t>(st.at("latency").at("min_ns")));
        out.stage_max_ns.push_back(whole<std::uint64_t>(st.at("latency").at("max_ns")));
        out.summary.stages.push_back(std::move(stage));
    }
}

// Files or runs merge cannot take, and why.
Error unmergeable(std::string why) {
    return Error(ErrorCode::InvalidInput, std::move(why));
}

}  // namespace

Error read_shard_summary(const std::string& path, ShardRun& out) {
    std::ifstream in(path);
    if (!in) return Error(ErrorCode::Io, fmt::format("{}: cannot open", path));
    try {
        const json doc = json::parse(in);
        out.json_path = path;
        read_test_object(doc, out);
        read_run_object(doc, out);
        read_counts_and_operations(doc, out);
        read_timeline(doc, out);
        read_connections(doc, out);
        read_shortfalls_and_thresholds(doc, out);
        read_stages(doc, out);
    } catch (const std::exception& e) {
        return unmergeable(
            fmt::format("{}: not a run's JSON summary mbstorm merge can read: {}", path, e.what()));
    }
    return Error::none();
}

Error read_shards(const std::vector<std::string>& files, std::vector<ShardRun>& out) {
    std::vector<ShardRun> runs;
    std::vector<std::pair<std::string, Hlog>> logs;
    for (const auto& path : files) {
        std::ifstream in(path);
        if (!in) return Error(ErrorCode::Io, fmt::format("{}: cannot open", path));
        char first = 0;
        in >> first;
        if (first == '{') {
            ShardRun run;
            if (Error bad = read_shard_summary(path, run); !bad.ok()) return bad;
            runs.push_back(std::move(run));
        } else if (first == '#' || first == '"' || first == 'T' || std::isdigit(first)) {
            // The header only (it names the run): the intervals are streamed when merged.
            in.seekg(0);
            HlogReader reader(in);
            if (!reader.read_header()) {
                return unmergeable(fmt::format("{}: {}", path, reader.error().text()));
            }
            logs.emplace_back(path, std::move(reader.header()));
        } else {
            return unmergeable(
                fmt::format("{}: neither a JSON summary (run --json) nor an interval log "
                            "(run --hlog)",
                            path));
        }
    }
    std::set<std::size_t> used;
    for (auto& run : runs) {
        for (std::size_t i = 0; i < logs.size(); ++i) {
            if (used.count(i) != 0 || log_run_id(logs[i].second) != run.summary.metadata.run_id)
                continue;
            used.insert(i);
            run.hlog_path = logs[i].first;
            run.log = std::move(logs[i].second);
            run.log_from_file = true;
            break;
        }
        if (run.hlog_path.empty()) {
            return unmergeable(
                fmt::format("{}: no interval log of this run given (run {}: pass the file "
                            "its --hlog wrote too)",
                            run.json_path, run.summary.metadata.run_id));
        }
        HlogIdentity id;
        find_hlog_identity(run.log, id);
        const int log_index = id.shard_count > 0 ? static_cast<int>(id.shard_index) : -1;
        if (static_cast<int>(id.shard_count) != run.shard_count ||
            (run.shard_count > 0 && log_index != run.shard_index)) {
            return unmergeable(fmt::format(
                "{}: its interval log {} says {}, the JSON {} (edited files?)", run.json_path,
                run.hlog_path, shard_text(log_index, static_cast<int>(id.shard_count)),
                shard_text(run.shard_index, run.shard_count)));
        }
    }
    for (std::size_t i = 0; i < logs.size(); ++i) {
        if (used.count(i) != 0) continue;
        const std::string id = log_run_id(logs[i].second);
        return unmergeable(
            id.empty() ? fmt::format("{}: not written by mbstorm run --hlog (no run id in "
                                     "its first line)",
                                     logs[i].first)
                       : fmt::format("{}: the interval log of run {}, whose JSON summary is "
                                     "not given (or is given once for two logs)",
                                     logs[i].first, id));
    }
    out = std::move(runs);
    return Error::none();
}

namespace {

// Identity: duplicates, other tests, other histogram settings. Empty when the runs are parts
// of one test.
std::string identity_refusal(const std::vector<ShardRun>& shards) {
    const ShardRun& first = shards.front();
    for (std::size_t i = 0; i < shards.size(); ++i) {
        const ShardRun& s = shards[i];
        for (std::size_t j = 0; j < i; ++j) {
            if (shards[j].summary.metadata.run_id == s.summary.metadata.run_id)
                return fmt::format("duplicate run: {} and {} are the same run ({})",
                                   shards[j].json_path, s.json_path, s.summary.metadata.run_id);
        }
        if (s.summary.metadata.test_id != first.summary.metadata.test_id)
            return fmt::format("{} is from another test: test id '{}', {} has '{}' (run --test-id)",
                               name_of(s), s.summary.metadata.test_id, name_of(first),
                               first.summary.metadata.test_id);
        if (plan_of(s) != plan_of(first))
            return fmt::format("{} is from another test: its plan is {}; {} has {}", name_of(s),
                               plan_of(s), name_of(first), plan_of(first));
        if (s.significant_digits != stats::Histogram::kSignificantDigits ||
            s.lowest_discernible_ns != 1 || s.highest_trackable_ns != first.highest_trackable_ns)
            return fmt::format(
                "different histogram settings: {} has {} significant digits, lowest {} ns, "
                "highest {} ns; {} has {}, {} ns, {} ns",
                name_of(s), s.significant_digits, s.lowest_discernible_ns, s.highest_trackable_ns,
                name_of(first), first.significant_digits, first.lowest_discernible_ns,
                first.highest_trackable_ns);
        if (s.threshold_expressions != first.threshold_expressions)
            return fmt::format("{} is from another test: its thresholds differ from {}'s",
                               name_of(s), name_of(first));
        if (s.summary.metadata.merged_runs != 0)
            return fmt::format("{} is itself a merged result: merge the runs' own files",
                               s.json_path);
    }
    return {};
}

// Shard numbers: each index 0..count-1 exactly once. Empty when whole.
std::string shard_set_refusal(const std::vector<ShardRun>& shards) {
    const ShardRun& first = shards.front();
    std::map<int, const ShardRun*> by_index;
    for (const auto& s : shards) {
        if (s.shard_index < 0 || s.shard_index >= s.shard_count)
            return fmt::format("{}: shard index {} outside 0..{}", name_of(s), s.shard_index,
                               s.shard_count - 1);
        if (auto [it, fresh] = by_index.emplace(s.shard_index, &s); !fresh)
            return fmt::format("duplicate shard {}: {} and {}", s.shard_index, name_of(*it->second),
                               name_of(s));
    }
    std::string missing;
    for (int i = 0; i < first.shard_count; ++i)
        if (by_index.count(i) == 0) missing += fmt::format("{}{}", missing.empty() ? "" : ", ", i);
    if (!missing.empty())
        return fmt::format("missing shards: {} of {} given, shard {} missing", shards.size(),
                           first.shard_count, missing);
    return {};
}

// Completeness: every shard once, or --expect's number of runs. Empty when whole.
std::string completeness_refusal(const std::vector<ShardRun>& shards, std::uint32_t expect_runs) {
    const ShardRun& first = shards.front();
    const bool numbered = first.shard_count > 0;
    for (const auto& s : shards) {
        if ((s.shard_count > 0) != numbered)
            return fmt::format(
                "{} is {}, {} is {}: shards merge only with the other shards of their test",
                name_of(s), shard_text(s.shard_index, s.shard_count), name_of(first),
                shard_text(first.shard_index, first.shard_count));
        if (s.shard_count != first.shard_count)
            return fmt::format("{} and {} disagree on the shard count ({} vs {})", name_of(s),
                               name_of(first), s.shard_count, first.shard_count);
    }
    if (numbered)
        if (std::string why = shard_set_refusal(shards); !why.empty()) return why;
    if (expect_runs != 0 && shards.size() != expect_runs)
        return fmt::format("{} runs given, --expect says the test has {}{}", shards.size(),
                           expect_runs, shards.size() < expect_runs ? ": missing runs" : "");
    return {};
}

// The merged run's metadata (the first run's plan over the span from origin to end, in epoch
// seconds), operations and stages with their counts cleared. True when the runs' stages merge
// into one table (all have as many).
bool shape_merged_run(const std::vector<ShardRun>& shards, std::uint64_t interval, double origin,
                      double end, stats::RunResult& out) {
    const ShardRun& first = shards.front();
    const auto& fm = first.summary.metadata;
    auto& m = out.metadata;
    m.tool_version = fm.tool_version;
    m.target = fm.target;
    m.depth = fm.depth;
    m.backend = fm.backend;
    m.model = fm.model;
    m.requested_duration_ns = fm.requested_duration_ns;
    m.warmup_ns = fm.warmup_ns;
    m.measured_duration_ns = ns_from_s(end - origin);
    m.coordinated_omission_corrected = fm.coordinated_omission_corrected;
    m.test_id = fm.test_id;
    m.merged_runs = static_cast<std::uint32_t>(shards.size());
    m.start_time = std::chrono::system_clock::time_point(
                       std::chrono::duration_cast<std::chrono::system_clock::duration>(
                           std::chrono::duration<double>(origin))) -
                   std::chrono::nanoseconds(m.warmup_ns);
    out.timeline_interval_ns = interval;
    out.operations = first.summary.operations;
    for (auto& op : out.operations) op.counters.reset();
    // Stages: names, places and counts from the JSONs, latencies from each log's stage lines.
    bool stages_merge = !first.summary.stages.empty();
    for (const auto& s : shards)
        stages_merge = stages_merge && s.summary.stages.size() == first.summary.stages.size();
    if (stages_merge) {
        out.stages = first.summary.stages;
        for (auto& st : out.stages) {
            st.counters.reset();
            st.rate_from = st.rate_to = 0.0;
            st.connections_from = st.connections_to = 0;
        }
    }
    return stages_merge;
}

// Exact extremes from the runs' JSONs (the logs only know buckets), narrowed into the merged
// histograms at the end.
struct Extremes {
    std::uint64_t min_ns = UINT64_MAX, max_ns = 0;
    std::vector<std::uint64_t> op_min, op_max, stage_min, stage_max;
    Extremes(std::size_t operations, std::size_t stages)
        : op_min(operations, UINT64_MAX),
          op_max(operations, 0),
          stage_min(stages, UINT64_MAX),
          stage_max(stages, 0) {}
    void narrow(stats::RunResult& out) const {
        out.latency.narrow_extremes(min_ns, max_ns);
        for (std::size_t i = 0; i < out.operations.size(); ++i)
            out.operations[i].latency.narrow_extremes(op_min[i], op_max[i]);
        for (std::size_t i = 0; i < out.stages.size(); ++i)
            out.stages[i].latency.narrow_extremes(stage_min[i], stage_max[i]);
    }
};

void add_connections(const stats::ConnectionStats& from, stats::ConnectionStats& c) {
    c.opened += from.opened;
    c.failed += from.failed;
    c.reconnects += from.reconnects;
    c.closed_by_peer += from.closed_by_peer;
    c.peak_open += from.peak_open;
    for (const auto& [name, count] : from.failed_by_cause) c.failed_by_cause[name] += count;
    c.tls_handshakes += from.tls_handshakes;
    c.tls_resumed += from.tls_resumed;
    c.tls_handshake_ns_total += from.tls_handshake_ns_total;
    c.tls_handshake_ns_max = std::max(c.tls_handshake_ns_max, from.tls_handshake_ns_max);
    c.tls_handshake_failures += from.tls_handshake_failures;
    c.tls_offloaded += from.tls_offloaded;
    c.tls_offload_errors += from.tls_offload_errors;
}

// A run's JSON counts by operation and stage into out's, with their exact extremes.
void add_operation_and_stage_counts(const ShardRun& s, stats::RunResult& out, Extremes& x) {
    for (std::size_t i = 0; i < out.operations.size(); ++i) {
        out.operations[i].counters.add(s.summary.operations[i].counters);
        if (s.op_max_ns[i] != 0 || s.op_min_ns[i] != 0) {
            x.op_min[i] = std::min(x.op_min[i], s.op_min_ns[i]);
            x.op_max[i] = std::max(x.op_max[i], s.op_max_ns[i]);
        }
    }
    for (std::size_t i = 0; i < out.stages.size(); ++i) {
        const stats::StageResult& from = s.summary.stages[i];
        stats::StageResult& into = out.stages[i];
        into.counters.add(from.counters);
        into.rate_from += from.rate_from;
        into.rate_to += from.rate_to;
        into.connections_from += from.connections_from;
        into.connections_to += from.connections_to;
        if (s.stage_max_ns[i] != 0 || s.stage_min_ns[i] != 0) {
            x.stage_min[i] = std::min(x.stage_min[i], s.stage_min_ns[i]);
            x.stage_max[i] = std::max(x.stage_max[i], s.stage_max_ns[i]);
        }
    }
}

// A run's JSON (everything but its timeline and log) added into out.
void add_run_summary(const ShardRun& s, stats::RunResult& out, Extremes& x) {
    const auto& sm = s.summary.metadata;
    auto& m = out.metadata;
    m.threads += sm.threads;
    m.connections += sm.connections;
    m.rate_per_second += sm.rate_per_second;
    for (const auto& note : sm.notes) m.notes.push_back(fmt::format("run {}: {}", sm.run_id, note));
    out.counters.add(s.summary.counters);
    add_operation_and_stage_counts(s, out, x);
    if (s.latency_count != 0) {
        x.min_ns = std::min(x.min_ns, s.min_ns);
        x.max_ns = std::max(x.max_ns, s.max_ns);
    }
    out.schedule_lag.engine.add(s.summary.schedule_lag.engine);
    out.schedule_lag.target.add(s.summary.schedule_lag.target);
    add_connections(s.summary.connections, out.connections);
    for (auto p : s.summary.shortfalls) {
        p.text = fmt::format("run {}: {}", sm.run_id, p.text);
        out.shortfalls.push_back(std::move(p));
    }
    out.pipelining.skipped_requests += s.summary.pipelining.skipped_requests;
}

// Where a run's intervals fall on the merged timeline, and how far its lines may start.
struct RunOnTimeline {
    double offset_s;     // the run's start after the earliest run's
    double run_s;        // its measured duration
    double allowance_s;  // a line may start this far outside [0, run_s]
    std::uint64_t interval_ns;

    RunOnTimeline(const ShardRun& s, double origin, std::uint64_t interval)
        : offset_s(s.measure_start_epoch_s - origin),
          run_s(static_cast<double>(s.summary.metadata.measured_duration_ns) / 1e9),
          allowance_s(static_cast<double>(interval) / 1e9 + kLineAllowanceSeconds),
          interval_ns(interval) {}
    // On the wall clock: a run's interval goes to the merged interval holding its middle.
    std::int64_t slot(double start_s) const {
        const double middle = offset_s + start_s + static_cast<double>(interval_ns) / 2e9;
        return static_cast<std::int64_t>(
            std::floor(middle * 1e9 / static_cast<double>(interval_ns)));
    }
    bool holds(double start_s, double length_s) const {
        return start_s >= -allowance_s && start_s <= run_s + allowance_s &&
               length_s <= run_s + allowance_s;
    }
};

// A run's JSON timeline into the merged intervals' counts. Empty, or why it is refused.
std::string add_timeline_counts(const ShardRun& s, const RunOnTimeline& place,
                                std::map<std::int64_t, SlotCounts>& counts) {
    for (const auto& iv : s.summary.timeline) {
        const double start_s = static_cast<double>(iv.start_offset_ns) / 1e9;
        if (!place.holds(start_s, 0.0))
            return fmt::format(
                "{}: timeline interval {} starts at {:.3f} s, after the run's own {:.3f} s "
                "(measured_duration_s)",
                s.json_path, iv.index, start_s, place.run_s);
        SlotCounts& into = counts[place.slot(start_s)];
        into.transactions += iv.transactions;
        into.errors += iv.errors;
        into.target_rate += iv.target_rate;
        into.open_connections += iv.open_connections;
    }
    return {};
}

// What a run's log gave: its untagged lines' places, whether it had stage lines.
struct LogPass {
    std::vector<SlotLine> untagged;
    bool stage_lines = false;
};

// A run's log, streamed: tagged lines added into their operation, stage lines into their
// stage, untagged lines noted (merged interval, position) for summarize_latency_slots.
// Empty, or why it is refused.
std::string add_log_lines(const ShardRun& s, std::uint32_t run_index, const RunOnTimeline& place,
                          IntervalLines& lines, HlogInterval& scratch, stats::RunResult& out,
                          LogPass& pass) {
    std::string why;
    pass.stage_lines = false;
    const bool read = lines.each(
        [&](const HlogInterval& line, std::uint64_t position) {
            if (!place.holds(line.start_s, line.length_s)) {
                why = fmt::format(
                    "{}: a line of {:.3f} s starting at {:.3f} s, outside the run's own {:.3f} s "
                    "(measured_duration_s of {})",
                    s.hlog_path, line.length_s, line.start_s, place.run_s, s.json_path);
                return false;
            }
            if (const std::uint32_t k = stage_of_hlog_tag(line.tag); k != 0) {
                pass.stage_lines = true;
                if (k <= out.stages.size()) out.stages[k - 1].latency.add(line.histogram);
            } else if (line.tag.empty()) {
                pass.untagged.push_back({place.slot(line.start_s), run_index, position});
            } else {
                for (auto& op : out.operations)
                    if (hlog_tag(op.name) == line.tag) op.latency.add(line.histogram);
            }
            return true;
        },
        scratch, why);
    return read ? std::string() : why;
}

// Every merged interval from the first to the last that holds anything (none before 0), gaps
// included, each without a histogram. The last runs to the end of the last run: runs that
// started apart end mid-interval, and their last stretch lands there.
void fill_timeline(const std::map<std::int64_t, SlotCounts>& counts,
                   const std::map<std::int64_t, stats::IntervalSummary>& latency,
                   stats::RunResult& out) {
    if (counts.empty() && latency.empty()) return;
    std::int64_t first_slot = INT64_MAX, last_slot = INT64_MIN;
    for (const std::int64_t k : {counts.empty() ? INT64_MAX : counts.begin()->first,
                                 latency.empty() ? INT64_MAX : latency.begin()->first})
        first_slot = std::min(first_slot, k);
    for (const std::int64_t k : {counts.empty() ? INT64_MIN : counts.rbegin()->first,
                                 latency.empty() ? INT64_MIN : latency.rbegin()->first})
        last_slot = std::max(last_slot, k);
    for (std::int64_t k = std::max<std::int64_t>(0, first_slot); k <= last_slot; ++k)
        out.timeline.push_back(merged_interval(k, out.timeline_interval_ns, counts, latency));
    const std::uint64_t measured = out.metadata.measured_duration_ns;
    if (!out.timeline.empty() && out.timeline.back().start_offset_ns < measured)
        out.timeline.back().duration_ns = measured - out.timeline.back().start_offset_ns;
}

// The per-stage table kept, or left out with a warning saying why.
void settle_stage_table(const std::vector<ShardRun>& shards, bool stages_merge,
                        const std::vector<std::string>& without_stage_lines, MergeOutcome& r) {
    const bool any_stages = std::any_of(
        shards.begin(), shards.end(), [](const ShardRun& s) { return !s.summary.stages.empty(); });
    if (!without_stage_lines.empty()) {
        r.warnings.push_back(fmt::format(
            "no per-stage table: the interval log of {} holds no stage histograms (an mbstorm "
            "that did not write them); the timeline shows the stages",
            without_stage_lines.front()));
        r.run.stages.clear();
    } else if (any_stages && !stages_merge) {
        r.warnings.push_back(
            "no per-stage table: the runs do not have the same stages; the timeline shows them");
    } else if (stages_merge) {
        r.run.metadata.notes.push_back(
            "per-stage table: each run's stage histograms (its interval log's stage lines) "
            "added, stage by stage, on each run's own clock");
    }
}

// The runs' span on the wall clock, epoch seconds: the earliest start, the latest end.
std::pair<double, double> span_of(const std::vector<ShardRun>& shards) {
    double origin = shards.front().measure_start_epoch_s, end = 0.0;
    for (const auto& s : shards) {
        origin = std::min(origin, s.measure_start_epoch_s);
        end = std::max(end, s.measure_start_epoch_s +
                                static_cast<double>(s.summary.metadata.measured_duration_ns) / 1e9);
    }
    return {origin, end};
}

}  // namespace

Result<MergeOutcome> merge_shards(std::vector<ShardRun> shards, std::uint32_t expect_runs) {
    MergeOutcome r;
    auto refuse = [](std::string why) { return unmergeable(std::move(why)); };
    if (shards.empty()) return refuse("no runs to merge");
    if (std::string why = identity_refusal(shards); !why.empty()) return refuse(why);
    if (std::string why = completeness_refusal(shards, expect_runs); !why.empty())
        return refuse(why);
    const std::uint64_t interval = shards.front().summary.timeline_interval_ns == 0
                                       ? 1'000'000'000
                                       : shards.front().summary.timeline_interval_ns;
    const auto [origin, end] = span_of(shards);
    if (const double slots = (end - origin) * 1e9 / static_cast<double>(interval);
        slots > kMaxTimelineSlots)
        return refuse(fmt::format(
            "the runs span {:.0f} s from the first start to the last end, {:.0f} intervals of "
            "{} s: more than the {:.0f} a merged timeline holds (runs of one test started days "
            "apart? each JSON's test.measure_start_epoch_s says when its run started)",
            end - origin, slots, static_cast<double>(interval) / 1e9, kMaxTimelineSlots));

    stats::RunResult& out = r.run;
    const bool stages_merge = shape_merged_run(shards, interval, origin, end, out);
    Extremes extremes(out.operations.size(), out.stages.size());
    std::map<std::int64_t, SlotCounts> counts_by_slot;
    std::vector<IntervalLines> logs(shards.begin(), shards.end());
    HlogInterval scratch;
    LogPass pass;
    std::vector<std::string> without_stage_lines;
    for (std::uint32_t run_index = 0; run_index < shards.size(); ++run_index) {
        const ShardRun& s = shards[run_index];
        add_run_summary(s, out, extremes);
        const RunOnTimeline place(s, origin, interval);
        if (std::string why = add_timeline_counts(s, place, counts_by_slot); !why.empty())
            return refuse(why);
        if (std::string why =
                add_log_lines(s, run_index, place, logs[run_index], scratch, out, pass);
            !why.empty())
            return refuse(why);
        if (!out.stages.empty() && !pass.stage_lines) without_stage_lines.push_back(name_of(s));
    }
    std::map<std::int64_t, stats::IntervalSummary> latency_by_slot;
    std::vector<std::uint64_t> logged(shards.size(), 0);
    if (std::string why; !summarize_latency_slots(pass.untagged, logs, interval, out.latency,
                                                  logged, latency_by_slot, why))
        return refuse(why);
    for (std::size_t i = 0; i < shards.size(); ++i)
        if (logged[i] != shards[i].latency_count)
            r.warnings.push_back(fmt::format(
                "{}: its interval log holds {} latencies, its JSON {} (a log cut short, or "
                "answers that came in after their interval was logged)",
                name_of(shards[i]), logged[i], shards[i].latency_count));
    extremes.narrow(out);
    fill_timeline(counts_by_slot, latency_by_slot, out);
    if (std::string w = overlap_warning(shards); !w.empty()) r.warnings.push_back(std::move(w));
    out.metadata.notes.push_back(fmt::format(
        "merged from {} runs (test '{}'): latencies from their interval logs' histograms, the "
        "timeline on wall-clock time from {}",
        shards.size(), out.metadata.test_id,
        format_utc(out.metadata.start_time + std::chrono::nanoseconds(out.metadata.warmup_ns))));
    settle_stage_table(shards, stages_merge, without_stage_lines, r);
    r.threshold_expressions = shards.front().threshold_expressions;
    return r;
}

}  // namespace mbstorm::report
