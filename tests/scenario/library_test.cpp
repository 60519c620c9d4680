// Every file in scenarios/ loads, validates, and runs for about a second (duration overridden,
// warmup cut short) against the embedded reference slave.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

#include "must_parse.hpp"
#include "scenario/runner.hpp"
#include "scenario/scenario.hpp"

namespace mbstorm::scenario {
namespace {

using namespace std::chrono_literals;

std::vector<std::string> library_files() {
    std::vector<std::string> files;
    // A path, not `string + literal`: g++ 12 warns falsely (-Warray-bounds) on the latter.
    const std::filesystem::path folder = std::filesystem::path(MBSTORM_SOURCE_DIR) / "scenarios";
    for (const auto& entry : std::filesystem::directory_iterator(folder)) {
        if (entry.path().extension() == ".yaml") files.push_back(entry.path().string());
    }
    std::sort(files.begin(), files.end());
    return files;
}

TEST(ScenarioLibrary, HasTheDocumentedFiles) {
    std::vector<std::string> names;
    for (const auto& f : library_files()) names.push_back(std::filesystem::path(f).stem().string());
    for (const char* expected : {"quickstart", "read-heavy", "mixed-read-write",
                                 "ramp-to-saturation", "many-connections", "soak", "ci-gate"}) {
        EXPECT_NE(std::find(names.begin(), names.end(), expected), names.end()) << expected;
    }
}

TEST(ScenarioLibrary, EveryFileLoadsAndRunsForASecond) {
    for (const auto& file : library_files()) {
        SCOPED_TRACE(file);
        Scenario s;
        ASSERT_NO_THROW(s = must_load(file));
        EXPECT_TRUE(s.target.empty()) << "library scenarios run against the embedded slave";
        Overrides o;
        o.duration = 1s;
        // The files' warmups (up to 10 s) would be most of the test's time; a short one still
        // runs that phase.
        if (s.plan.warmup > 200ms) o.warmup = 200ms;
        o.slave_threads = 1;
        o.threads = 1;
        // many-connections.yaml asks for 10k connections: more file descriptors than a test
        // machine allows (the embedded slave doubles them), so it runs with 200 here.
        if (s.plan.connections > 200) o.connections = 200;
        const Error problems = apply_overrides(s, o);
        ASSERT_TRUE(problems.ok()) << problems.text();
        EXPECT_EQ(s.total_duration(), 1s);
        const load::LoadResult r = run_scenario(s);
        ASSERT_TRUE(r.ok()) << r.error;
        EXPECT_GT(r.run.counters.ok(), 0U);
        EXPECT_EQ(r.run.counters.count(stats::Outcome::ValueMismatch), 0U);
        EXPECT_EQ(r.run.counters.count(stats::Outcome::Exception), 0U);
        EXPECT_EQ(r.run.thresholds.size(), s.thresholds.size());
        EXPECT_EQ(r.run.stages.size(), s.stages.size());
    }
}

}  // namespace
}  // namespace mbstorm::scenario
