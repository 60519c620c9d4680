// One duration syntax for every subcommand (compound forms, bare numbers in each flag's own
// unit), and numeric flags that refuse NaN and infinity and state their range in words.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "../support/run_mbstorm.hpp"

using mbstorm::test::run_mbstorm;
using testing::HasSubstr;
using testing::Not;

namespace {

// The largest double, as CLI11's ranges print it: never shown to a user.
constexpr const char* kLargestDouble = "1.79769e+308";

TEST(Durations, RunTakesCompoundDurations) {
    auto r = run_mbstorm("run -d 1s200ms -c 1 --depth 1 -q", 60);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_THAT(r.output, HasSubstr("duration 1.2s")) << r.output;
}

TEST(Durations, FuzzSecondsTakesADuration) {
    // Nothing listens on port 1: the run fails on the target, not on "--seconds 2s".
    auto r = run_mbstorm("fuzz --target 127.0.0.1:1 --seconds 2s --timeout 200ms -q", 60);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_THAT(r.output, HasSubstr("127.0.0.1:1")) << r.output;
    EXPECT_THAT(r.output, Not(HasSubstr("--seconds"))) << r.output;
    EXPECT_THAT(r.output, Not(HasSubstr(kLargestDouble)));
}

TEST(Durations, FuzzTakesDurationLikeRun) {
    auto r = run_mbstorm("fuzz --target 127.0.0.1:1 -d 1m30s --timeout 200ms -q", 60);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_THAT(r.output, Not(HasSubstr("--duration"))) << r.output;
}

TEST(Durations, ServeStopsByItselfAndPrintsItsSummary) {
    auto r = run_mbstorm("serve --listen 127.0.0.1:0 --threads 1 --duration 1s200ms", 60);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_THAT(r.output, HasSubstr("summary:")) << r.output;
}

// -d 300ms is 300 ms of serving, not the next whole second (the loop waited for its
// once-a-second statistics line before looking at the deadline: it printed "summary: 1.0s").
TEST(Durations, ServeEndsAtItsDurationNotAtTheNextSecond) {
    auto r = run_mbstorm("serve --listen 127.0.0.1:0 --threads 1 -d 300ms", 60);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    const auto at = r.output.find("summary: ");
    ASSERT_NE(at, std::string::npos) << r.output;
    const double seconds = std::stod(r.output.substr(at + 9));
    EXPECT_GE(seconds, 0.3) << r.output;
    EXPECT_LT(seconds, 1.0) << r.output;
}

TEST(Durations, BadDurationsNameTheForms) {
    for (const char* args :
         {"run -d nan", "run -d 1m30", "fuzz --target 127.0.0.1:1 --seconds nan",
          "fuzz --target 127.0.0.1:1 --seconds inf", "serve --duration 2parsecs"}) {
        auto r = run_mbstorm(args, 30);
        EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.output;
        EXPECT_THAT(r.output, HasSubstr("1m30s")) << args << "\n" << r.output;
    }
}

TEST(Numbers, NanAndInfinityAreRefusedWithTheRangeInWords) {
    struct Case {
        const char* args;
        const char* range;
    };
    for (const Case& c : {Case{"run --rate nan", "a number from 0 to 1,000,000,000"},
                          Case{"run --rate inf", "a number from 0 to 1,000,000,000"},
                          Case{"run --rate -5", "a number from 0 to 1,000,000,000"},
                          Case{"run --zipf nan", "a number from 0 to 10"},
                          Case{"run --connect-rate infinity", "a number from 1 to 10,000,000"}}) {
        auto r = run_mbstorm(c.args, 30);
        EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.output;
        EXPECT_THAT(r.output, HasSubstr(c.range)) << c.args << "\n" << r.output;
        EXPECT_THAT(r.output, Not(HasSubstr(kLargestDouble))) << c.args;
    }
}

TEST(Numbers, CountsRefuseZeroWithoutTheLargestDouble) {
    auto r = run_mbstorm("fuzz --target 127.0.0.1:1 --cases 0", 30);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_THAT(r.output, HasSubstr("at least 1")) << r.output;
    EXPECT_THAT(r.output, Not(HasSubstr(kLargestDouble)));
}

}  // namespace
