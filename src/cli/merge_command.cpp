// `mbstorm merge FILE...`: the runs of one test (each run's --json and --hlog files) as one
// report, as if one machine had run the whole plan (the merging is report/merge.cpp's), with
// the thresholds judged on the merged result and run's exit codes.
#include <fmt/format.h>

#include <cstdio>
#include <string>
#include <vector>

#include "cli/commands.hpp"
#include "cli/run_output.hpp"
#include "report/files.hpp"
#include "report/merge.hpp"
#include "scenario/runner.hpp"
#include "scenario/scenario.hpp"
#include "scenario/threshold.hpp"

namespace mbstorm::cli {
namespace {

struct MergeOptions {
    std::vector<std::string> files;
    std::string scenario_file;
    std::uint32_t expect = 0;
    OutputFiles outputs;
};

// The runs' own threshold expressions ("p99 < 5ms", "read: p99 < 5ms") as specs.
Error thresholds_from_runs(const std::vector<std::string>& expressions, const stats::RunResult& run,
                           scenario::Scenario& s) {
    for (const auto& e : expressions) {
        std::string text = e;
        std::string operation;
        if (const auto colon = e.find(": "); colon != std::string::npos) {
            for (const auto& op : run.operations) {
                if (op.name == e.substr(0, colon)) {
                    operation = op.name;
                    text = e.substr(colon + 2);
                }
            }
        }
        Result<scenario::ThresholdSpec> spec = scenario::parse_threshold(text);
        if (!spec.ok())
            return std::move(spec).error().prefixed(fmt::format("threshold '{}' of the runs", e));
        spec->operation = operation;
        s.thresholds.push_back(std::move(spec).value());
    }
    return Error::none();
}

int merge(const MergeOptions& o) {
    if (const Error conflict = stdout_conflict(o.outputs); !conflict.ok())
        return usage_error("merge", conflict.text());
    for (const std::string* path :
         {&o.outputs.json, &o.outputs.hdr, &o.outputs.html, &o.outputs.junit}) {
        if (!path->empty() && *path != "-")
            if (Error bad = report::check_writable(*path); !bad.ok())
                return usage_error("merge", "cannot write " + bad.text());
    }
    std::vector<report::ShardRun> shards;
    if (Error bad = report::read_shards(o.files, shards); !bad.ok())
        return usage_error("merge", bad.text());
    Result<report::MergeOutcome> outcome = report::merge_shards(std::move(shards), o.expect);
    if (!outcome.ok()) return usage_error("merge", outcome.error().text());
    report::MergeOutcome& merged = *outcome;
    std::string error;
    for (const auto& w : merged.warnings) fmt::print(stderr, "mbstorm merge: warning: {}\n", w);

    scenario::Scenario s;
    if (!o.scenario_file.empty()) {
        Result<scenario::Scenario> loaded = scenario::load_scenario_file(o.scenario_file);
        if (!loaded.ok()) return fail("merge", loaded.error());
        s = std::move(loaded).value();
    } else if (Error e = thresholds_from_runs(merged.threshold_expressions, merged.run, s);
               !e.ok()) {
        return fail("merge", e);
    }
    scenario::evaluate_thresholds(s, merged.run);

    load::LoadResult result;
    result.run = std::move(merged.run);
    fmt::print(stderr, "mbstorm merge: {} runs of test '{}'{}\n", result.run.metadata.merged_runs,
               result.run.metadata.test_id,
               result.run.thresholds.empty()
                   ? ""
                   : fmt::format(", {} thresholds judged on the merged result",
                                 result.run.thresholds.size()));
    OutputFiles files = o.outputs;
    files.junit_suite = s.name.empty() ? "mbstorm merge" : s.name;
    int code = report_run(result, files);
    if (code == kExitOk && !result.run.thresholds_passed()) {
        std::size_t failed = 0;
        for (const auto& t : result.run.thresholds) failed += t.passed ? 0 : 1;
        fmt::print(stderr, "mbstorm merge: {} of {} threshold{} breached\n", failed,
                   result.run.thresholds.size(), result.run.thresholds.size() == 1 ? "" : "s");
        code = kExitFailed;
    }
    return code;
}

}  // namespace

void add_merge_command(CLI::App& app, Action& action) {
    auto o = std::make_shared<MergeOptions>();
    auto* cmd = app.add_subcommand(
        "merge",
        "Combine the runs of one test (each run's --json and --hlog files) into one report, "
        "as if one machine had run the whole plan; thresholds judged on the merged result");
    cmd->add_option("files", o->files,
                    "every run's JSON summary (run --json) and interval log (run --hlog)")
        ->required();
    cmd->add_option("--scenario", o->scenario_file,
                    "judge this scenario's thresholds (default: the thresholds the runs carry)");
    cmd->add_option("--expect", o->expect,
                    "the number of runs the test has: fewer or more is refused")
        ->check(CLI::Range(1u, 100000u));
    add_output_options(cmd, o->outputs);
    cmd->add_option("--junit", o->outputs.junit,
                    "write the thresholds as JUnit XML test cases ('-': stdout)");
    cmd->callback([&action, o] { action = [o] { return merge(*o); }; });
}

}  // namespace mbstorm::cli
