// One meaning per flag: across every subcommand, a flag name (-q, --count, ...) stands for one
// option, spelt the same way, taking a value or not alike, with the same choices. Walks the
// CLI11 definition the binary parses (cli::add_all_commands), so a new flag is checked too.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "../support/run_mbstorm.hpp"
#include "cli/commands.hpp"

namespace mbstorm::cli {
namespace {

// What a user can tell of an option from the command line: all its spellings, whether it takes
// a value, and the values it accepts when they are a fixed set ("closed|open").
std::string shape_of(const CLI::Option& opt) {
    std::vector<std::string> names;
    for (const std::string& s : opt.get_snames()) names.push_back("-" + s);
    for (const std::string& l : opt.get_lnames()) names.push_back("--" + l);
    std::sort(names.begin(), names.end());
    std::string shape;
    for (const std::string& n : names) shape.append(shape.empty() ? "" : ",").append(n);
    if (opt.get_expected_max() == 0) return shape;
    shape += " VALUE";
    // An IsMember check shows in the type name as "TEXT:{a,b,c}".
    const std::string type = opt.get_type_name();
    if (auto open = type.find(":{"); open != std::string::npos) shape += type.substr(open + 1);
    return shape;
}

// Flag names whose options differ in shape between subcommands but mean one thing, and why.
const std::map<std::string, std::string> kSameMeaning = {
    {"--duration", "fuzz keeps --seconds, its first spelling of how long to run"},
    {"-d", "fuzz keeps --seconds, its first spelling of how long to run"},
    {"--json",
     "JSON out: read and write stream one object per transaction to stdout (they poll "
     "until stopped), run, fuzz and merge write one document to FILE or '-'"},
};

// flag name -> shape -> the subcommands that define it so.
using Uses = std::map<std::string, std::map<std::string, std::vector<std::string>>>;

Uses uses_of_every_flag() {
    CLI::App app;
    Action action;
    add_all_commands(app, action);
    Uses uses;
    for (const CLI::App* sub : app.get_subcommands({})) {
        for (const CLI::Option* opt : sub->get_options()) {
            // Positionals have no flag name; deprecated spellings (hidden, group "") keep their
            // old meaning on purpose, with a warning.
            if (!opt->nonpositional() || opt->get_group().empty()) continue;
            std::vector<std::string> names;
            for (const std::string& s : opt->get_snames()) names.push_back("-" + s);
            for (const std::string& l : opt->get_lnames()) names.push_back("--" + l);
            for (const std::string& name : names)
                uses[name][shape_of(*opt)].push_back(sub->get_name());
        }
    }
    return uses;
}

TEST(CliFlags, EveryFlagNameHasOneMeaningInEverySubcommand) {
    const Uses uses = uses_of_every_flag();
    ASSERT_GT(uses.size(), 50u) << "the walk found too few flags to be the whole command line";
    for (const auto& [name, shapes] : uses) {
        if (shapes.size() == 1 || kSameMeaning.count(name) != 0) continue;
        std::string found;
        for (const auto& [shape, subs] : shapes)
            found += "\n  " + shape + " in " + testing::PrintToString(subs);
        ADD_FAILURE() << name << " means different things:" << found;
    }
}

// The spellings the one-meaning rule retired keep their old meaning, with one line on stderr.
TEST(CliFlags, OldSpellingsKeepTheirMeaningAndNameTheNewOne) {
    using test::run_mbstorm;
    const std::string frame = run_mbstorm("encode --fc 3 --addr 0 --quantity 5").output;
    ASSERT_EQ(frame, "00 01 00 00 00 06 01 03 00 00 00 05\n");
    EXPECT_EQ(run_mbstorm("encode --fc 3 --addr 0 --count 5").output,
              "mbstorm encode: --count is deprecated, use --quantity\n" + frame);
    EXPECT_EQ(run_mbstorm("encode --fc 3 --addr 0 -n 5").output,
              "mbstorm encode: -n is deprecated, use --quantity\n" + frame);
    const auto scenario = run_mbstorm("run --count 7 --print-scenario");
    EXPECT_EQ(scenario.exit_code, 0) << scenario.output;
    EXPECT_THAT(scenario.output, testing::HasSubstr("run: --count is deprecated, use --quantity"));
    EXPECT_THAT(scenario.output, testing::HasSubstr("quantity: 7"));
    const auto serve = run_mbstorm("serve -t 1 --listen 127.0.0.1:0 -d 1", 30);
    EXPECT_EQ(serve.exit_code, 0) << serve.output;
    EXPECT_THAT(serve.output, testing::HasSubstr("serve: -t is deprecated, use --threads"));
    EXPECT_THAT(serve.output, testing::HasSubstr("(tcp, 1 thread,"));
    const auto fuzz = run_mbstorm("fuzz --target 127.0.0.1:1 --model /nonexistent --cases 1");
    EXPECT_THAT(fuzz.output, testing::HasSubstr("fuzz: --model is deprecated, use --device-model"));
    EXPECT_THAT(fuzz.output, testing::HasSubstr("--device-model /nonexistent: cannot read it"));
}

TEST(CliFlags, ReadHelpTellsMbpollUsersWhereTheUnitIs) {
    const auto help = test::run_mbstorm("read --help").output;
    EXPECT_THAT(help, testing::HasSubstr("mbpoll's -a"));
    EXPECT_THAT(help, testing::HasSubstr("the unit is -u"));
}

TEST(CliFlags, AllowWritesAndAllowRemoteEachSuggestTheOther) {
    EXPECT_EQ(test::run_mbstorm("fuzz --target 192.0.2.1 --allow-writes").output,
              "mbstorm fuzz: unknown option --allow-writes; did you mean --allow-remote?\n");
    EXPECT_EQ(test::run_mbstorm("run --allow-remote").output,
              "mbstorm run: unknown option --allow-remote; did you mean --allow-writes?\n");
}

}  // namespace
}  // namespace mbstorm::cli
