// `mbstorm run`'s load-model flags: contradictions among --model, --rate and --arrival are
// usage errors naming both flags, as the same settings are in a scenario file.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>

#include "../support/run_mbstorm.hpp"

using mbstorm::test::run_mbstorm;
using testing::HasSubstr;

namespace {

TEST(LoadModelFlags, ContradictionsAreUsageErrorsNamingBothFlags) {
    struct Case {
        const char* args;
        const char* message;
    };
    for (const Case& c : {Case{"run --model closed --rate 100 -d 1s -q",
                               "--model closed and --rate 100 contradict each other"},
                          Case{"run --arrival poisson -d 1s -q", "--arrival poisson needs --rate"},
                          Case{"run --model closed --arrival poisson -d 1s -q",
                               "--arrival poisson contradicts --model closed"},
                          Case{"run --model open -d 1s -q", "--model open needs --rate"}}) {
        auto r = run_mbstorm(c.args, 30);
        EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.output;
        EXPECT_THAT(r.output, HasSubstr(c.message)) << c.args;
        EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << c.args << "\n"
                                                                         << r.output;
    }
}

TEST(LoadModelFlags, ConsistentFlagsRun) {
    for (const char* args : {"run --rate 200 --arrival poisson -d 300ms -c 1 --depth 1 -q",
                             "run --model open --rate 200 -d 300ms -c 1 --depth 1 -q",
                             "run --model closed -d 300ms -c 1 --depth 1 -q"}) {
        auto r = run_mbstorm(args, 60);
        EXPECT_EQ(r.exit_code, 0) << args << "\n" << r.output;
    }
}

}  // namespace
