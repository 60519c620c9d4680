// A target that leaves requests unanswered at random (`mbstorm serve --no-answer-rate`): one
// finding, drops-requests-at-random, that replays; not one hang per request it happened to
// drop, each saved as confirmed and replaying 0 of 5 (issue #26 item 5, #29 item 6).
#include <gtest/gtest.h>

#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "fuzz_test_support.hpp"

namespace {

using mbstorm::test::run_mbstorm;

TEST(RandomDrops, ATargetThatDropsRequestsAtRandomIsOneFindingThatReplays) {
    std::unique_ptr<mbstorm::test::Target> server;
    const std::string target =
        mbstorm::test::start_reference_slave(server, {"--no-answer-rate", "0.3", "--seed", "5"});
    ASSERT_FALSE(target.empty());
    const std::string dir = mbstorm::test::temp_dir("random-drops");
    const auto run =
        run_mbstorm("fuzz --target " + target + " --seconds 15 --timeout 200ms --seed 1 -q --out " +
                    dir + "/findings --json " + dir + "/s.json");
    ASSERT_EQ(run.exit_code, 1) << run.output;
    std::ifstream in(dir + "/s.json");
    const auto s = nlohmann::json::parse(in);
    ASSERT_EQ(s.at("findings").size(), 1u) << run.output;
    const auto& f = s.at("findings").at(0);
    EXPECT_EQ(f.at("root_cause"), "hang:drops-requests-at-random") << run.output;
    EXPECT_TRUE(f.at("confirmed").get<bool>());
    const auto replay = run_mbstorm("replay " + f.at("folder").get<std::string>() + " --target " +
                                    target + " --runs 3");
    EXPECT_EQ(replay.exit_code, 1) << replay.output;
    EXPECT_NE(replay.output.find("3 of 3 run(s) reproduced the finding (the case as found: it "
                                 "was not minimised)"),
              std::string::npos)
        << replay.output;
}

// Learning the map of a target that drops one request in ten (a lossy link, a busy gateway):
// a silence is asked again before it is taken for an address outside the map, so the reference
// slave's whole map is learned, every table and unit, with no holes (before, hundreds of holes
// and tables left empty, and a finding per invented hole: "a read over address N answered
// normally, where a read of that address alone gets 02").
TEST(RandomDrops, TheMapOfATargetThatDropsRequestsIsLearnedWithoutHoles) {
    std::unique_ptr<mbstorm::test::Target> server;
    const std::string target =
        mbstorm::test::start_reference_slave(server, {"--no-answer-rate", "0.1", "--seed", "5"});
    ASSERT_FALSE(target.empty());
    const std::string dir = mbstorm::test::temp_dir("lossy-map");
    // 4 s to learn (a tenth of --seconds); the run ends after 500 cases.
    const auto run = run_mbstorm("fuzz --target " + target +
                                 " --seconds 40 --cases 500 --timeout 200ms --seed 1 -q --out " +
                                 dir + "/findings --json " + dir + "/s.json");
    std::ifstream in(dir + "/s.json");
    const auto s = nlohmann::json::parse(in, nullptr, false);
    ASSERT_FALSE(s.is_discarded()) << run.output;
    const auto& model = s.at("model");
    EXPECT_FALSE(model.at("partial").get<bool>()) << run.output;
    for (const char* table : {"coils", "discrete-inputs", "input-registers", "holding-registers"})
        EXPECT_EQ(model.at("tables").at(table).at("ranges"), nlohmann::json::parse("[[0,65535]]"))
            << table << "\n"
            << run.output;
    EXPECT_EQ(model.at("units").size(), 256u) << run.output;
    for (const auto& f : s.at("findings"))
        EXPECT_EQ(f.at("root_cause"), "hang:drops-requests-at-random") << run.output;
}

}  // namespace
