// Scenario bombs: huge files and huge counts are refused with their position, and naming many
// unnamed operations of one function is linear (it was worse than quadratic: 40k took 128 s).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "../support/run_mbstorm.hpp"
#include "scenario/operation_names.hpp"
#include "scenario/scenario.hpp"

namespace mbstorm::scenario {
namespace {

using testing::HasSubstr;

std::string many_unnamed_operations(std::size_t count) {
    std::string text = "operations:\n";
    for (std::size_t i = 0; i < count; ++i) text += "  - function: read_holding_registers\n";
    return text;
}

TEST(OperationNames, DefaultNamesOfOneFunctionAreFoundInLinearProbes) {
    OperationNames names;
    ASSERT_TRUE(names.add_explicit("read_3"));  // taken ahead: skipped once, not every time
    constexpr std::size_t kCount = 40000;
    for (std::size_t i = 0; i < kCount; ++i) names.add_default("read");
    // One probe per name, plus one for the explicit name in the way. The old search started at
    // _2 every time: kCount * (kCount + 1) / 2 probes.
    EXPECT_EQ(names.probes(), kCount + 1);
    EXPECT_EQ(names.all().size(), kCount + 1);
    EXPECT_TRUE(names.contains("read"));
    EXPECT_TRUE(names.contains("read_2"));
    EXPECT_TRUE(names.contains("read_40001"));
}

TEST(OperationNames, EachDefaultNameHasItsOwnSuffixes) {
    OperationNames names;
    EXPECT_EQ(names.add_default("a"), "a");
    EXPECT_EQ(names.add_default("b"), "b");
    EXPECT_EQ(names.add_default("a"), "a_2");
    ASSERT_TRUE(names.add_explicit("b_2"));
    EXPECT_EQ(names.add_default("b"), "b_3");
    EXPECT_FALSE(names.add_explicit("a_2"));
}

TEST(ScenarioCaps, UnnamedOperationsUpToTheCapGetSuffixes) {
    const Scenario s = parse_scenario(many_unnamed_operations(kMaxOperations), "many.yaml");
    ASSERT_EQ(s.plan.operations.size(), kMaxOperations);
    EXPECT_EQ(s.plan.operations[1].name, "read_holding_registers_2");
    EXPECT_EQ(s.plan.operations.back().name,
              "read_holding_registers_" + std::to_string(kMaxOperations));
}

TEST(ScenarioCaps, TooManyOperationsNamesTheFirstOnePastTheCap) {
    try {
        parse_scenario(many_unnamed_operations(kMaxOperations + 5), "many.yaml");
        FAIL() << "accepted";
    } catch (const ScenarioError& e) {
        EXPECT_THAT(e.what(), HasSubstr("too many operations: 1005 (at most 1000)"));
        EXPECT_EQ(e.line(), static_cast<int>(kMaxOperations) + 2);  // after "operations:"
        EXPECT_EQ(e.column(), 5);
    }
}

TEST(ScenarioCaps, TooManyStagesAndThresholds) {
    std::string stages = "operations: [{function: read_holding_registers}]\nstages:\n";
    for (std::size_t i = 0; i <= kMaxStages; ++i) stages += "  - {duration: 1s, rate: 10}\n";
    EXPECT_THROW(
        {
            try {
                parse_scenario(stages, "s.yaml");
            } catch (const ScenarioError& e) {
                EXPECT_THAT(e.what(), HasSubstr("too many stages"));
                EXPECT_GT(e.line(), 0);
                throw;
            }
        },
        ScenarioError);
    std::string thresholds = "operations: [{function: read_holding_registers}]\nthresholds:\n";
    for (std::size_t i = 0; i <= kMaxThresholds; ++i) thresholds += "  - p99 < 5ms\n";
    EXPECT_THROW(parse_scenario(thresholds, "t.yaml"), ScenarioError);
}

TEST(ScenarioCaps, AFileLargerThanTheCapIsRefusedWithExitTwo) {
    const auto path = std::filesystem::path(::testing::TempDir()) / "mbstorm_huge_scenario.yaml";
    {
        std::ofstream out(path);
        out << "name: \"";
        const std::string block(64 * 1024, 'x');
        for (std::size_t written = 0; written <= kMaxScenarioBytes; written += block.size())
            out << block;
        out << "\"\noperations: [{function: read_holding_registers}]\n";
    }
    try {
        load_scenario_file(path.string());
        FAIL() << "accepted";
    } catch (const ScenarioError& e) {
        EXPECT_THAT(e.what(), HasSubstr(path.string() + ":1:1: the scenario file is larger than "
                                                        "4 MiB"));
    }
    const auto r = test::run_mbstorm("run " + path.string() + " -q", 60);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_THAT(r.output, HasSubstr(path.string() + ":1:1:"));
    std::filesystem::remove(path);
}

}  // namespace
}  // namespace mbstorm::scenario
