// `mbstorm run` in CI without a scenario file (issue #29): --threshold (the scenario's
// expression language, repeatable), --junit for them, and --fail-on-plan-shortfall.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "../support/run_mbstorm.hpp"

using mbstorm::test::run_mbstorm;
using testing::HasSubstr;

namespace {

std::string read_file(const std::filesystem::path& p) {
    std::ifstream in(p);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

std::filesystem::path scratch(const char* name) {
    return std::filesystem::temp_directory_path() /
           (std::string(name) + "-" + std::to_string(::getpid()) + ".xml");
}

// A passing and a breached threshold against the embedded slave: exit 1, both in the JUnit
// file as test cases, the breached one a failure.
TEST(RunCiFlags, ThresholdsFromTheCommandLineJudgeTheRunAndGoToJunit) {
    const auto junit = scratch("ci-thresholds");
    auto r = run_mbstorm(
        "run -d 500ms -c 1 --depth 1 -q --threshold 'p99 < 10s' "
        "--threshold 'throughput > 1000000000/s' --junit " +
            junit.string(),
        60);
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_THAT(r.output, HasSubstr("1 of 2 thresholds breached"));
    const std::string xml = read_file(junit);
    EXPECT_THAT(xml, HasSubstr("tests=\"2\" failures=\"1\"")) << xml;
    EXPECT_THAT(xml, HasSubstr("name=\"p99 &lt; 10s\"")) << xml;
    std::filesystem::remove(junit);
    auto pass = run_mbstorm("run -d 300ms -c 1 --depth 1 -q --threshold 'error_rate < 1%'", 60);
    EXPECT_EQ(pass.exit_code, 0) << pass.output;
}

// A bad expression is a usage error naming it; --junit with nothing to judge is one too.
TEST(RunCiFlags, ABadThresholdOrAJunitWithNothingToJudgeIsAUsageError) {
    auto bad = run_mbstorm("run -d 300ms -q --threshold 'p99 <'", 30);
    EXPECT_EQ(bad.exit_code, 2) << bad.output;
    EXPECT_THAT(bad.output, HasSubstr("--threshold 'p99 <'"));
    auto none = run_mbstorm("run -d 300ms -q --junit " + scratch("ci-none").string(), 30);
    EXPECT_EQ(none.exit_code, 2) << none.output;
    EXPECT_THAT(none.output, HasSubstr("give --threshold EXPR"));
}

// An open-loop rate nobody can reach: without the flag the run passes (it reports the
// shortfall); with it the run fails, saying what was missing.
TEST(RunCiFlags, APlanNotCarriedOutFailsTheRunOnlyWhenAsked) {
    const char* unreachable = "run -d 500ms -c 1 --depth 1 --rate 100000000 -q";
    auto plain = run_mbstorm(unreachable, 60);
    EXPECT_EQ(plain.exit_code, 0) << plain.output;
    auto strict = run_mbstorm(std::string(unreachable) + " --fail-on-plan-shortfall", 60);
    EXPECT_EQ(strict.exit_code, 1) << strict.output;
    EXPECT_THAT(strict.output, HasSubstr("plan carried out (--fail-on-plan-shortfall)"));
    EXPECT_THAT(strict.output, HasSubstr("of the 50,000,000 transactions"));
    // A closed loop carried out (one connection, the whole duration) passes: a low open-loop
    // rate is no test of it, its 5% slack is a transaction or two on a loaded host.
    auto met = run_mbstorm("run -d 500ms -c 1 --depth 1 -q --fail-on-plan-shortfall", 60);
    EXPECT_EQ(met.exit_code, 0) << met.output;
}

}  // namespace
