// A target that serves one connection at a time (the next waits in the listen backlog, as in
// libmodbus's simplest server loop and many small devices), restarted within 10 ms by a
// supervisor when it crashes. No idle sentinel connection can be held beside the fuzzer's, so
// the death is told by a marker register losing the value mbstorm wrote (issue #26 item 3);
// cases that need two connections at once are not sent, and the backlog is reported once, by
// the capacity check.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "fuzz_test_support.hpp"

namespace {

using mbstorm::test::run_mbstorm;
using mbstorm::test::tool_path;

TEST(OneConnection, ACrashUnderAFastSupervisorIsACrashToldByTheMarkerRegister) {
    auto server = std::make_unique<mbstorm::test::Target>(std::vector<std::string>{
        tool_path("broken_server_crash"), "--respawn", "--restart-delay-ms", "10",
        "--one-connection", "--exit-after-s", "200"});
    const std::string line = server->wait_for_line("PORT ");
    ASSERT_FALSE(line.empty());
    const std::string target = "127.0.0.1:" + line.substr(5);
    const std::string dir = mbstorm::test::temp_dir("one-connection");
    const auto run = run_mbstorm("fuzz --target " + target + " --seconds 20 --seed 1 -q --out " +
                                 dir + "/findings --json " + dir + "/s.json");
    ASSERT_EQ(run.exit_code, 1) << run.output;
    std::ifstream in(dir + "/s.json");
    const auto s = nlohmann::json::parse(in);
    EXPECT_TRUE(s.at("one_connection_at_a_time").get<bool>()) << run.output;
    EXPECT_FALSE(s.at("death_watch").get<bool>());
    EXPECT_FALSE(s.at("death_marker").is_null()) << run.output;
    const std::set<std::string> expected = {"crash:target-down/fc0F",
                                            "hang:capacity/accepted-connections-unserved"};
    std::set<std::string> found;
    for (const auto& f : s.at("findings")) {
        const std::string key = f.at("root_cause").get<std::string>();
        EXPECT_TRUE(found.insert(key).second) << "twice: " << key;
        EXPECT_TRUE(expected.count(key)) << "not planted: " << f.dump(2);
        EXPECT_LE(f.at("restarts").get<unsigned>(), 3u) << f.dump(2);
        EXPECT_TRUE(f.at("confirmed").get<bool>()) << f.dump(2);
        // Replay watches the same way: the marker register, no sentinels.
        const auto replay = run_mbstorm(
            "replay " + f.at("folder").get<std::string>() + " --target " + target + " --runs 2",
            60);
        EXPECT_NE(replay.output.find("2 of 2 run(s) reproduced"), std::string::npos)
            << key << "\n"
            << replay.output;
    }
    EXPECT_EQ(found, expected) << run.output;
    std::filesystem::remove_all(dir);
}

}  // namespace
