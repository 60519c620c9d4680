// Scenario bombs: huge files and huge counts are refused with their position, and naming many
// unnamed operations of one function is linear (it was worse than quadratic: 40k took 128 s).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "../support/run_mbstorm.hpp"
#include "must_parse.hpp"
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
    const Scenario s = must_parse(many_unnamed_operations(kMaxOperations), "many.yaml");
    ASSERT_EQ(s.plan.operations.size(), kMaxOperations);
    EXPECT_EQ(s.plan.operations[1].name, "read_holding_registers_2");
    EXPECT_EQ(s.plan.operations.back().name,
              "read_holding_registers_" + std::to_string(kMaxOperations));
}

TEST(ScenarioCaps, TooManyOperationsNamesTheFirstOnePastTheCap) {
    const Error e =
        parse_scenario(many_unnamed_operations(kMaxOperations + 5), "many.yaml").error();
    ASSERT_FALSE(e.ok()) << "accepted";
    EXPECT_EQ(e.code(), ErrorCode::InvalidInput);
    EXPECT_THAT(e.message(), HasSubstr("too many operations: 1005 (at most 1000)"));
    // The line after "operations:" and the first, column 5.
    EXPECT_EQ(e.place(), "many.yaml:" + std::to_string(kMaxOperations + 2) + ":5");
}

TEST(ScenarioCaps, TooManyStagesAndThresholds) {
    std::string stages = "operations: [{function: read_holding_registers}]\nstages:\n";
    for (std::size_t i = 0; i <= kMaxStages; ++i) stages += "  - {duration: 1s, rate: 10}\n";
    const Error too_many_stages = parse_scenario(stages, "s.yaml").error();
    EXPECT_THAT(too_many_stages.text(), HasSubstr("too many stages"));
    EXPECT_THAT(too_many_stages.place(), testing::StartsWith("s.yaml:"));
    std::string thresholds = "operations: [{function: read_holding_registers}]\nthresholds:\n";
    for (std::size_t i = 0; i <= kMaxThresholds; ++i) thresholds += "  - p99 < 5ms\n";
    EXPECT_FALSE(parse_scenario(thresholds, "t.yaml").ok());
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
    const Error e = load_scenario_file(path.string()).error();
    EXPECT_EQ(e.code(), ErrorCode::InvalidInput);
    EXPECT_EQ(e.place(), path.string() + ":1:1");
    EXPECT_THAT(e.text(), HasSubstr(path.string() + ":1:1: the scenario file is larger than "
                                                    "4 MiB"));
    const auto r = test::run_mbstorm("run " + path.string() + " -q", 60);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_THAT(r.output, HasSubstr(path.string() + ":1:1:"));
    std::filesystem::remove(path);
}

}  // namespace
}  // namespace mbstorm::scenario
