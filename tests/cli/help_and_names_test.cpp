// Help that teaches: no subcommand prints the usage, a misspelt subcommand or option names the
// one meant, and every parse error names its subcommand.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sstream>

#include <string>

#include "../support/run_mbstorm.hpp"

using mbstorm::test::run_mbstorm;
using testing::HasSubstr;
using testing::Not;
using testing::StartsWith;

namespace {

constexpr int kExitUsage = 2;

TEST(CliHelp, NoArgumentsPrintsTheUsageAndEverySubcommand) {
    const auto r = run_mbstorm("");
    EXPECT_EQ(r.exit_code, kExitUsage);
    EXPECT_THAT(r.output, HasSubstr("Usage:"));
    EXPECT_THAT(r.output, HasSubstr("Subcommands:"));
    for (const char* sub :
         {"run", "serve", "decode", "encode", "fuzz", "replay", "read", "write", "merge"})
        EXPECT_THAT(r.output, HasSubstr(std::string("\n  ") + sub + " ")) << sub;
    EXPECT_THAT(r.output, HasSubstr("mbstorm SUBCOMMAND --help"));
}

TEST(CliNames, MisspeltSubcommandSuggestsTheNearestOne) {
    const auto r = run_mbstorm("rnu");
    EXPECT_EQ(r.exit_code, kExitUsage);
    EXPECT_EQ(r.output, "mbstorm: unknown subcommand 'rnu'; did you mean 'run'?\n");
    EXPECT_THAT(run_mbstorm("fuz --target 127.0.0.1").output, HasSubstr("did you mean 'fuzz'?"));
}

TEST(CliNames, UnknownSubcommandFarFromAnyListsThemAll) {
    const auto r = run_mbstorm("xyzzy");
    EXPECT_EQ(r.exit_code, kExitUsage);
    EXPECT_THAT(r.output,
                HasSubstr("mbstorm: unknown subcommand 'xyzzy'; the subcommands are "
                          "run, serve, decode, encode, fuzz, replay, read, write, merge"));
}

TEST(CliNames, MisspeltOptionSuggestsTheOptionOfThatSubcommand) {
    const auto r = run_mbstorm("run --conections 4");
    EXPECT_EQ(r.exit_code, kExitUsage);
    // Not taken for the scenario file's path any more ("file: File does not exist: 4").
    EXPECT_EQ(r.output, "mbstorm run: unknown option --conections; did you mean --connections?\n");
    EXPECT_THAT(run_mbstorm("fuzz --target 127.0.0.1 --max-conections 3").output,
                HasSubstr("mbstorm fuzz: unknown option --max-conections; did you mean "
                          "--max-connections?"));
    EXPECT_THAT(run_mbstorm("serve --theads=2").output,
                HasSubstr("mbstorm serve: unknown option --theads; did you mean --threads?"));
}

TEST(CliNames, UnknownOptionFarFromAnyPointsToTheHelp) {
    const auto r = run_mbstorm("run -x 4");
    EXPECT_EQ(r.exit_code, kExitUsage);
    EXPECT_EQ(r.output, "mbstorm run: unknown option -x (see mbstorm run --help)\n");
    EXPECT_EQ(run_mbstorm("run ---").output,
              "mbstorm run: unknown option --- (see mbstorm run --help)\n");
    EXPECT_THAT(run_mbstorm("decode --frobnicate 01").output,
                HasSubstr("mbstorm decode: unknown option --frobnicate (see mbstorm decode "
                          "--help)"));
}

TEST(CliNames, ValuesAndKnownSpellingsAreNotTakenForOptions) {
    // --name=value, a negative number and what follows "--" are values, not unknown options.
    const auto r = run_mbstorm("run --seed=5 --connections=3 --print-scenario");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_THAT(run_mbstorm("encode --fc 6 --addr 0 --value -1").output,
                HasSubstr("mbstorm encode: --value: Value -1 not in range"));
    EXPECT_THAT(run_mbstorm("decode --pdu -- -z").output, Not(HasSubstr("unknown option")));
}

// Every subcommand's --help ends with examples that start with its own name and the exit
// codes it uses (the man pages take both as sections: script.man_pages).
TEST(CliHelp, EverySubcommandHasExamplesAndExitStatus) {
    const auto all = run_mbstorm("--help");
    const auto list = all.output.substr(all.output.find("Subcommands:"));
    std::istringstream lines(list);
    std::string line;
    int checked = 0;
    while (std::getline(lines, line)) {
        if (line.rfind("  ", 0) != 0 || line.size() < 3 || line[2] == ' ') continue;
        const std::string sub = line.substr(2, line.find(' ', 2) - 2);
        const auto help = run_mbstorm(sub + " --help");
        EXPECT_THAT(help.output, HasSubstr("\nExamples:\n  mbstorm " + sub)) << sub;
        EXPECT_THAT(help.output, HasSubstr("\nExit status:\n  0  ")) << sub;
        ++checked;
    }
    EXPECT_GE(checked, 9) << all.output;
}

// A packaged scenario runs by its name; a name that is neither a file nor packaged says where
// the packaged ones are.
TEST(CliHelp, APackagedScenarioRunsByName) {
    const auto ok = run_mbstorm("run quickstart --print-scenario");
    EXPECT_EQ(ok.exit_code, 0) << ok.output;
    EXPECT_THAT(ok.output, HasSubstr("scenarios/quickstart.yaml"));
    const auto none = run_mbstorm("run no-such-scenario -q");
    EXPECT_EQ(none.exit_code, 2) << none.output;
    EXPECT_THAT(none.output, HasSubstr("no scenario file 'no-such-scenario' (nor a packaged "));
}

TEST(CliHelp, ParseErrorsNameTheSubcommand) {
    const auto r = run_mbstorm("run --connections 0");
    EXPECT_EQ(r.exit_code, kExitUsage);
    EXPECT_THAT(r.output, StartsWith("mbstorm run: --connections: Value 0 not in range"));
    EXPECT_THAT(run_mbstorm("read --unit").output, StartsWith("mbstorm read: "));
    EXPECT_THAT(run_mbstorm("completion fish").output, StartsWith("mbstorm completion: "));
}

}  // namespace
