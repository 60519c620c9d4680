#include "cli/run_scenario.hpp"

#include <fmt/format.h>
#include <signal.h>

#include <atomic>
#include <cstdio>
#include <memory>
#include <random>
#include <thread>
#include <utility>

#include "cli/commands.hpp"
#include "cli/metrics_endpoint.hpp"
#include "report/files.hpp"
#include "report/hlog.hpp"
#include "report/prometheus.hpp"
#include "report/timeline_stream.hpp"
#include "report/units.hpp"
#include "scenario/print.hpp"
#include "scenario/runner.hpp"

namespace mbstorm::cli {
namespace {

std::atomic<bool> g_scenario_stop{false};
std::atomic<int> g_scenario_signal{0};  // which signal stopped the run

extern "C" void on_scenario_stop_signal(int signal_number) {
    g_scenario_signal.store(signal_number, std::memory_order_relaxed);
    g_scenario_stop.store(true, std::memory_order_relaxed);
    // A second Ctrl-C ends the process at once.
    signal(SIGINT, SIG_DFL);
    signal(SIGTERM, SIG_DFL);
}

// 64 random bits in hex: tells this run apart from every other (merge refuses duplicates).
std::string new_run_id() {
    std::random_device device;
    const std::uint64_t bits = (std::uint64_t{device()} << 32) ^ device();
    return fmt::format("{:016x}", bits);
}

// --hlog: each interval's lines (all operations, then one per operation) as it completes.
load::IntervalHistogramsCallback hlog_lines(report::HlogWriter& writer,
                                            const scenario::Scenario& s) {
    std::vector<std::string> tags;
    for (const auto& op : s.plan.operations) tags.push_back(report::hlog_tag(op.name));
    // Every tag has its line in every interval: empty when the interval had no tag histograms.
    auto empty = std::make_shared<const stats::Histogram>();
    return [&writer, tags, empty](const stats::IntervalHistograms& interval,
                                  std::chrono::system_clock::time_point measure_start) {
        writer.start(measure_start);
        const double start = static_cast<double>(interval.start_offset_ns) / 1e9;
        const double length = static_cast<double>(interval.duration_ns) / 1e9;
        writer.write_interval("", start, length, interval.all);
        for (std::size_t i = 0; i < tags.size(); ++i)
            writer.write_interval(tags[i], start, length,
                                  i < interval.by_tag.size() ? interval.by_tag[i] : *empty);
        writer.end_interval();
    };
}

// "shard 1/3: 5 of the plan's connections, 1000 tx/s, 3334 transactions".
std::string describe_shard(const load::Plan& part) {
    std::string text =
        fmt::format("shard {}/{}: {} connection{}", part.shard.index, part.shard.count,
                    part.connections, part.connections == 1 ? "" : "s");
    if (part.model == load::LoadModel::OpenLoop && part.rate > 0)
        text += fmt::format(", {:.6g} tx/s", part.rate);
    if (part.transactions != 0) text += fmt::format(", {} transactions", part.transactions);
    if (!part.stages.empty()) text += ", its share of every stage";
    return text;
}

void announce_start(std::chrono::system_clock::time_point at) {
    const double ahead =
        std::chrono::duration<double>(at - std::chrono::system_clock::now()).count();
    fmt::print(stderr, "mbstorm run: connecting now, sending from {} ({})\n",
               report::format_utc(at),
               ahead >= 0 ? fmt::format("in {:.1f}s", ahead)
                          : fmt::format("{:.1f}s ago: starting at once", -ahead));
}

// --metrics-linger: the final values stay up until one scrape after the end has read them (a
// scraper whose interval falls after the run would otherwise never see them), at most `ns`.
void linger_for_a_scrape(const net::HttpServer& metrics, const std::atomic<std::uint64_t>& scrapes,
                         std::uint64_t ns) {
    const std::uint64_t before = scrapes.load(std::memory_order_relaxed);
    fmt::print(stderr,
               "mbstorm run: final metrics at http://{}/metrics until scraped (at most {:.0f}s)\n",
               metrics.address(), static_cast<double>(ns) / 1e9);
    std::fflush(stderr);
    signal(SIGINT, on_scenario_stop_signal);
    signal(SIGTERM, on_scenario_stop_signal);
    const auto until = std::chrono::steady_clock::now() + std::chrono::nanoseconds(ns);
    while (scrapes.load(std::memory_order_relaxed) == before && !g_scenario_stop.load() &&
           std::chrono::steady_clock::now() < until)
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    signal(SIGINT, SIG_DFL);
    signal(SIGTERM, SIG_DFL);
}

}  // namespace

std::string add_threshold_flags(const std::vector<std::string>& texts, scenario::Scenario& s) {
    for (const std::string& text : texts) {
        scenario::ThresholdSpec spec;
        std::string error;
        if (!scenario::parse_threshold(text, spec, error))
            return fmt::format("--threshold '{}': {}", text, error);
        s.thresholds.push_back(std::move(spec));
    }
    return {};
}

int print_flag_scenario(const load::Plan& plan, const std::string& target,
                        const std::vector<std::string>& thresholds) {
    scenario::Scenario s = scenario::scenario_from_plan(plan, target);
    if (auto e = add_threshold_flags(thresholds, s); !e.empty()) return usage_error("run", e);
    fmt::print("{}", scenario::format_scenario(s));
    return kExitOk;
}

namespace {

// --fail-on-plan-shortfall: the plan carried out is one more check, failed when a part of it
// (connections, rate, duration) was not (its text says what was missing).
void judge_plan_carried_out(stats::RunResult& run) {
    stats::ThresholdResult t;
    t.expression = "plan carried out (--fail-on-plan-shortfall)";
    t.passed = run.shortfalls.empty();
    t.observed = t.passed ? 1.0 : 0.0;
    for (const stats::PlanShortfall& s : run.shortfalls)
        t.observed_text += (t.observed_text.empty() ? "" : "; ") + s.text;
    if (t.passed) t.observed_text = "yes";
    run.thresholds.push_back(std::move(t));
}

}  // namespace

int run_resolved_scenario(const scenario::Scenario& s, const ScenarioRunRequest& request) {
    // A report that cannot be written must not cost a whole run first.
    const std::pair<const char*, const std::string*> outputs[] = {
        {"--json", &request.outputs.json},         {"--hdr", &request.outputs.hdr},
        {"--html", &request.outputs.html},         {"--hlog", &request.outputs.hlog},
        {"--timeline", &request.outputs.timeline}, {"--junit", &request.junit}};
    for (const auto& [flag, path] : outputs) {
        if (!path->empty() && *path != "-")
            if (Error bad = report::check_writable(*path); !bad.ok())
                return usage_error("run", fmt::format("cannot write {} {}", flag, bad.text()));
    }
    if (request.outputs.hlog == "-")
        return usage_error("run", "--hlog needs a file (it is written as the run goes)");
    if (request.outputs.timeline == "-")
        return usage_error("run", "--timeline needs a file (it is written as the run goes)");
    const load::Plan::Shard shard = request.shard;
    if (shard.count != 0) {
        const load::ShardedPlan part = scenario::engine_plan(s, shard);
        if (!part.error.empty()) return usage_error("run", part.error);
        fmt::print(stderr, "mbstorm run: {}\n", describe_shard(part.plan));
    }
    if (request.start_at) announce_start(*request.start_at);
    const std::string run_id = new_run_id();
    report::HlogWriter hlog;
    if (!request.outputs.hlog.empty()) {
        const std::string identity =
            report::hlog_identity_text({request.outputs.test_id, run_id, shard.index, shard.count});
        if (Error bad = hlog.open(request.outputs.hlog, identity); !bad.ok())
            return usage_error("run", fmt::format("cannot write --hlog {}", bad.text()));
    }
    report::TimelineWriter timeline;
    if (!request.outputs.timeline.empty()) {
        if (Error bad = timeline.open(request.outputs.timeline, request.outputs.test_id, run_id);
            !bad.ok())
            return usage_error("run", fmt::format("cannot write --timeline {}", bad.text()));
    }
    load::LiveMetrics live(request.outputs.test_id,
                           shard.count != 0 ? fmt::format("{}", shard.index) : std::string());
    net::HttpServer metrics;
    std::atomic<std::uint64_t> scrapes{0};  // /metrics answers, for --metrics-linger
    if (!request.outputs.metrics_listen.empty() &&
        !start_metrics_endpoint(metrics, request.outputs.metrics_listen, "run", [&live, &scrapes] {
            scrapes.fetch_add(1, std::memory_order_relaxed);
            return report::format_load_metrics(live.snapshot());
        }))
        return kExitUsage;
    g_scenario_stop = false;
    g_scenario_signal = 0;
    signal(SIGINT, on_scenario_stop_signal);
    signal(SIGTERM, on_scenario_stop_signal);
    LiveProgress progress(stderr, request.quiet);
    scenario::RunHooks hooks;
    hooks.stop = &g_scenario_stop;
    hooks.tool_version = "mbstorm 0.1.0";
    hooks.on_progress = [&progress](const load::ProgressSnapshot& snap) { progress.update(snap); };
    hooks.on_message = [](const std::string& m) { fmt::print(stderr, "mbstorm run: {}\n", m); };
    if (hlog.is_open()) hooks.on_interval_histograms = hlog_lines(hlog, s);
    if (metrics.running()) hooks.live = &live;
    if (timeline.is_open())
        hooks.on_interval = [&timeline](const stats::IntervalSummary& interval,
                                        std::chrono::system_clock::time_point measure_start) {
            timeline.write(interval, measure_start);
        };
    hooks.shard = shard;
    hooks.start_at = request.start_at;
    hooks.backend = request.backend;
    load::LoadResult result = scenario::run_scenario(s, hooks);
    if (request.fail_on_plan_shortfall) judge_plan_carried_out(result.run);
    result.run.metadata.test_id = request.outputs.test_id;
    result.run.metadata.run_id = run_id;
    if (const auto late = result.run.metadata.late_by_ns; late != 0)
        fmt::print(stderr, "mbstorm run: started {:.3f}s late (after --start-at): began at once\n",
                   static_cast<double>(late) / 1e9);
    bool stream_failed = false;
    if (hlog.is_open()) {
        // A run that never started still leaves a valid (empty) log.
        const auto start = result.run.metadata.start_time;
        if (!hlog.started())
            hlog.start(start.time_since_epoch().count() != 0 ? start
                                                             : std::chrono::system_clock::now());
        // Each stage's whole histogram last, tagged: the per-stage table of a merge.
        for (const stats::StageResult& stage : result.run.stages) {
            hlog.write_interval(
                report::hlog_stage_tag(stage.index),
                static_cast<double>(stage.start_offset_ns) / 1e9,
                static_cast<double>(stage.end_offset_ns - stage.start_offset_ns) / 1e9,
                stage.latency);
            hlog.end_interval();
        }
        if (Error bad = hlog.close(); !bad.ok()) {
            fmt::print(stderr, "mbstorm run: cannot write --hlog {}: {}\n", request.outputs.hlog,
                       bad.text());
            stream_failed = true;
        } else {
            fmt::print(stderr, "wrote HdrHistogram interval log {}\n", request.outputs.hlog);
        }
    }
    if (timeline.is_open()) {
        if (Error bad = timeline.close(); !bad.ok()) {
            fmt::print(stderr, "mbstorm run: cannot write --timeline {}: {}\n",
                       request.outputs.timeline, bad.text());
            stream_failed = true;
        } else {
            fmt::print(stderr, "wrote timeline {}\n", request.outputs.timeline);
        }
    }
    progress.finish();
    signal(SIGINT, SIG_DFL);
    signal(SIGTERM, SIG_DFL);
    const int stopped_by = g_scenario_signal.load();
    if (stopped_by != 0)
        result.run.metadata.notes.push_back(
            fmt::format("interrupted by {}", signal_name(stopped_by)));

    OutputFiles files = request.outputs;
    files.junit = request.junit;
    files.junit_suite = s.name.empty() ? std::string("run") : s.name;
    int code = report_run(result, files);
    if (stream_failed && code == kExitOk) code = kExitUsage;
    if (code == kExitOk && !result.run.thresholds_passed()) {
        std::size_t failed = 0;
        for (const auto& t : result.run.thresholds) failed += t.passed ? 0 : 1;
        if (shard.count != 0) {
            // A shard's thresholds see its part only ("throughput > X" cannot pass on a third
            // of the load): the verdict is mbstorm merge's, on the whole test.
            fmt::print(stderr,
                       "mbstorm run: shard {}/{}: {} of {} threshold{} breached on this shard's "
                       "part (not a verdict: mbstorm merge judges the whole test)\n",
                       shard.index, shard.count, failed, result.run.thresholds.size(),
                       result.run.thresholds.size() == 1 ? "" : "s");
        } else {
            fmt::print(stderr, "mbstorm run: {} of {} threshold{} breached\n", failed,
                       result.run.thresholds.size(), result.run.thresholds.size() == 1 ? "" : "s");
            code = kExitFailed;
        }
    }
    if (stopped_by != 0) {
        // Reports are written above; the exit code says the run did not finish.
        fmt::print(stderr, "mbstorm run: interrupted by {}: exit code {}\n",
                   signal_name(stopped_by), exit_code_for_signal(stopped_by));
        if (code != kExitUsage) code = exit_code_for_signal(stopped_by);
    }
    if (metrics.running() && request.outputs.metrics_linger_ns != 0 && stopped_by == 0)
        linger_for_a_scrape(metrics, scrapes, request.outputs.metrics_linger_ns);
    return code;
}

int run_scenario_file(const ScenarioRunRequest& request) {
    scenario::Scenario s;
    try {
        s = scenario::load_scenario_file(request.file);
    } catch (const scenario::ScenarioError& e) {
        return usage_error("run", e.what());
    }
    if (const auto problems = scenario::apply_overrides(s, request.overrides); !problems.empty()) {
        for (const auto& p : problems) fmt::print(stderr, "mbstorm run: {}\n", p);
        return kExitUsage;
    }
    if (auto e = add_threshold_flags(request.thresholds, s); !e.empty())
        return usage_error("run", e);
    if (request.print) {
        fmt::print("{}", scenario::format_scenario(s));
        return kExitOk;
    }
    if (request.tls && s.target.empty())
        return usage_error("run",
                           "--transport tls needs a target (the embedded slave is plain TCP)");
    s.plan.tls = request.tls;
    s.plan.tls_resume = request.tls_resume;
    if (!request.serial.device.empty()) {
        // One master on the line, one request at a time (see serial_load.hpp).
        s.target.clear();
        s.plan.serial = request.serial;
        s.plan.connections = 1;
        s.plan.depth = 1;
        s.plan.threads = 1;
    }

    const auto& plan = s.plan;
    fmt::print(
        stderr,
        "mbstorm run: scenario '{}' ({}){}: {} operation{}, {} connection{} x depth {}, {}, "
        "{}{}\n",
        s.name, request.file,
        !plan.serial.device.empty()
            ? fmt::format(" on serial line {}", plan.serial.device)
            : (s.target.empty() ? " against the embedded reference slave (no target given)" : ""),
        plan.operations.size(), plan.operations.size() == 1 ? "" : "s", plan.connections,
        plan.connections == 1 ? "" : "s", plan.depth,
        plan.model == load::LoadModel::OpenLoop ? "open loop" : "closed loop",
        s.stages.empty() ? "" : fmt::format("{} stages, ", s.stages.size()),
        fmt::format("{:.3g}s", std::chrono::duration<double>(s.total_duration()).count()));

    return run_resolved_scenario(s, request);
}

}  // namespace mbstorm::cli
