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

Error add_threshold_flags(const std::vector<std::string>& texts, scenario::Scenario& s) {
    for (const std::string& text : texts) {
        Result<scenario::ThresholdSpec> spec = scenario::parse_threshold(text);
        if (!spec.ok())
            return std::move(spec).error().prefixed(fmt::format("--threshold '{}'", text));
        s.thresholds.push_back(std::move(spec).value());
    }
    return {};
}

int print_flag_scenario(const load::Plan& plan, const std::string& target,
                        const std::vector<std::string>& thresholds) {
    scenario::Scenario s = scenario::scenario_from_plan(plan, target);
    if (const Error e = add_threshold_flags(thresholds, s); !e.ok())
        return usage_error("run", e.text());
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

// A report that cannot be written must not cost a whole run first.
Error check_outputs(const ScenarioRunRequest& request) {
    const std::pair<const char*, const std::string*> outputs[] = {
        {"--json", &request.outputs.json},         {"--hdr", &request.outputs.hdr},
        {"--html", &request.outputs.html},         {"--hlog", &request.outputs.hlog},
        {"--timeline", &request.outputs.timeline}, {"--junit", &request.junit}};
    for (const auto& [flag, path] : outputs) {
        if (path->empty() || *path == "-") continue;
        if (Error bad = report::check_writable(*path); !bad.ok())
            return Error(bad.code(), fmt::format("cannot write {} {}", flag, bad.text()));
    }
    if (request.outputs.hlog == "-")
        return Error(ErrorCode::InvalidInput,
                     "--hlog needs a file (it is written as the run goes)");
    if (request.outputs.timeline == "-")
        return Error(ErrorCode::InvalidInput,
                     "--timeline needs a file (it is written as the run goes)");
    return {};
}

// --hlog and --timeline: the files written as the run goes, interval by interval.
class RunStreams {
  public:
    Error open(const ScenarioRunRequest& request, const std::string& run_id) {
        const OutputFiles& outputs = request.outputs;
        if (!outputs.hlog.empty()) {
            const std::string identity = report::hlog_identity_text(
                {outputs.test_id, run_id, request.shard.index, request.shard.count});
            if (Error bad = hlog_.open(outputs.hlog, identity); !bad.ok())
                return Error(bad.code(), fmt::format("cannot write --hlog {}", bad.text()));
        }
        if (outputs.timeline.empty()) return {};
        if (Error bad = timeline_.open(outputs.timeline, outputs.test_id, run_id); !bad.ok())
            return Error(bad.code(), fmt::format("cannot write --timeline {}", bad.text()));
        return {};
    }

    void hook(const scenario::Scenario& s, scenario::RunHooks& hooks) {
        if (hlog_.is_open()) hooks.on_interval_histograms = hlog_lines(hlog_, s);
        if (timeline_.is_open())
            hooks.on_interval = [this](const stats::IntervalSummary& interval,
                                       std::chrono::system_clock::time_point measure_start) {
                timeline_.write(interval, measure_start);
            };
    }

    // Finishes both files, saying so on stderr; false when one could not be written.
    bool close(const stats::RunResult& run, const OutputFiles& outputs) {
        bool written = true;
        if (hlog_.is_open()) {
            add_stage_histograms(run);
            if (Error bad = hlog_.close(); !bad.ok()) {
                fmt::print(stderr, "mbstorm run: cannot write --hlog {}: {}\n", outputs.hlog,
                           bad.text());
                written = false;
            } else {
                fmt::print(stderr, "wrote HdrHistogram interval log {}\n", outputs.hlog);
            }
        }
        if (timeline_.is_open()) {
            if (Error bad = timeline_.close(); !bad.ok()) {
                fmt::print(stderr, "mbstorm run: cannot write --timeline {}: {}\n",
                           outputs.timeline, bad.text());
                written = false;
            } else {
                fmt::print(stderr, "wrote timeline {}\n", outputs.timeline);
            }
        }
        return written;
    }

  private:
    // Each stage's whole histogram last, tagged: the per-stage table of a merge. A run that
    // never started still leaves a valid (empty) log.
    void add_stage_histograms(const stats::RunResult& run) {
        const auto start = run.metadata.start_time;
        if (!hlog_.started())
            hlog_.start(start.time_since_epoch().count() != 0 ? start
                                                              : std::chrono::system_clock::now());
        for (const stats::StageResult& stage : run.stages) {
            hlog_.write_interval(
                report::hlog_stage_tag(stage.index),
                static_cast<double>(stage.start_offset_ns) / 1e9,
                static_cast<double>(stage.end_offset_ns - stage.start_offset_ns) / 1e9,
                stage.latency);
            hlog_.end_interval();
        }
    }

    report::HlogWriter hlog_;
    report::TimelineWriter timeline_;
};

// The engine's hooks: stop on a signal, progress on stderr, streams and live metrics fed.
scenario::RunHooks run_hooks(const ScenarioRunRequest& request, LiveProgress& progress,
                             load::LiveMetrics* live) {
    scenario::RunHooks hooks;
    hooks.stop = &g_scenario_stop;
    hooks.tool_version = "mbstorm 0.1.0";
    hooks.on_progress = [&progress](const load::ProgressSnapshot& snap) { progress.update(snap); };
    hooks.on_message = [](const std::string& m) { fmt::print(stderr, "mbstorm run: {}\n", m); };
    hooks.live = live;
    hooks.shard = request.shard;
    hooks.start_at = request.start_at;
    hooks.backend = request.backend;
    return hooks;
}

// Ctrl-C (SIGINT) and SIGTERM end the run early, reports written (a second one at once).
void catch_stop_signals() {
    g_scenario_stop = false;
    g_scenario_signal = 0;
    signal(SIGINT, on_scenario_stop_signal);
    signal(SIGTERM, on_scenario_stop_signal);
}

// The signal that stopped the run, or 0.
int stop_catching_signals() {
    signal(SIGINT, SIG_DFL);
    signal(SIGTERM, SIG_DFL);
    return g_scenario_signal.load();
}

// The thresholds' verdict on top of the reports' exit code: a shard's breaches are no
// verdict (mbstorm merge judges the whole test).
int judge_thresholds(const stats::RunResult& run, load::Plan::Shard shard, int code) {
    if (code != kExitOk || run.thresholds_passed()) return code;
    std::size_t failed = 0;
    for (const auto& t : run.thresholds) failed += t.passed ? 0 : 1;
    const std::size_t all = run.thresholds.size();
    if (shard.count != 0) {
        // A shard's thresholds see its part only ("throughput > X" cannot pass on a third
        // of the load): the verdict is mbstorm merge's, on the whole test.
        fmt::print(stderr,
                   "mbstorm run: shard {}/{}: {} of {} threshold{} breached on this shard's "
                   "part (not a verdict: mbstorm merge judges the whole test)\n",
                   shard.index, shard.count, failed, all, all == 1 ? "" : "s");
        return code;
    }
    fmt::print(stderr, "mbstorm run: {} of {} threshold{} breached\n", failed, all,
               all == 1 ? "" : "s");
    return kExitFailed;
}

// Reports are written before: the exit code says the run did not finish (128 + the signal),
// unless a report could not be written.
int note_interrupt(int stopped_by, int code) {
    if (stopped_by == 0) return code;
    fmt::print(stderr, "mbstorm run: interrupted by {}: exit code {}\n", signal_name(stopped_by),
               exit_code_for_signal(stopped_by));
    return code == kExitUsage ? code : exit_code_for_signal(stopped_by);
}

// The metadata the command line adds: which test and run, and a late start.
void note_run(const ScenarioRunRequest& request, const std::string& run_id, stats::RunResult& run) {
    run.metadata.test_id = request.outputs.test_id;
    run.metadata.run_id = run_id;
    if (const auto late = run.metadata.late_by_ns; late != 0)
        fmt::print(stderr, "mbstorm run: started {:.3f}s late (after --start-at): began at once\n",
                   static_cast<double>(late) / 1e9);
}

}  // namespace

int run_resolved_scenario(const scenario::Scenario& s, const ScenarioRunRequest& request) {
    if (Error e = check_outputs(request); !e.ok()) return fail("run", e);
    const load::Plan::Shard shard = request.shard;
    if (shard.count != 0) {
        const Result<load::Plan> part = scenario::engine_plan(s, shard);
        if (!part.ok()) return fail("run", part.error());
        fmt::print(stderr, "mbstorm run: {}\n", describe_shard(*part));
    }
    if (request.start_at) announce_start(*request.start_at);
    const std::string run_id = new_run_id();
    RunStreams streams;
    if (Error e = streams.open(request, run_id); !e.ok()) return fail("run", e);
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
    LiveProgress progress(stderr, request.quiet);
    scenario::RunHooks hooks = run_hooks(request, progress, metrics.running() ? &live : nullptr);
    streams.hook(s, hooks);
    catch_stop_signals();
    load::LoadResult result = scenario::run_scenario(s, hooks);
    if (request.fail_on_plan_shortfall) judge_plan_carried_out(result.run);
    note_run(request, run_id, result.run);
    const bool streams_written = streams.close(result.run, request.outputs);
    progress.finish();
    const int stopped_by = stop_catching_signals();
    if (stopped_by != 0)
        result.run.metadata.notes.push_back(
            fmt::format("interrupted by {}", signal_name(stopped_by)));

    OutputFiles files = request.outputs;
    files.junit = request.junit;
    files.junit_suite = s.name.empty() ? std::string("run") : s.name;
    int code = report_run(result, files);
    if (!streams_written && code == kExitOk) code = kExitUsage;
    code = note_interrupt(stopped_by, judge_thresholds(result.run, shard, code));
    if (metrics.running() && request.outputs.metrics_linger_ns != 0 && stopped_by == 0)
        linger_for_a_scrape(metrics, scrapes, request.outputs.metrics_linger_ns);
    return code;
}

int run_scenario_file(const ScenarioRunRequest& request) {
    Result<scenario::Scenario> loaded = scenario::load_scenario_file(request.file);
    if (!loaded.ok()) return fail("run", loaded.error());
    scenario::Scenario s = std::move(loaded).value();
    if (Error e = scenario::apply_overrides(s, request.overrides); !e.ok()) return fail("run", e);
    if (const Error e = add_threshold_flags(request.thresholds, s); !e.ok())
        return usage_error("run", e.text());
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
