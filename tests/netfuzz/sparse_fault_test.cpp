// The fuzzer on a device like the ones users have (tests/tools/sparse_device_server.cpp): a
// small sparse map from address 1000 with a hole, 100 ms of pause and a flush after exceptions
// 01 and 03, thirteen planted bugs, and a supervisor that restarts it within ~20 ms of a crash
// (as systemd or a container runtime would; no --restart-cmd). With a fixed seed: the map is
// learned, every planted bug it can reach is found exactly once, every crash is called a crash
// however fast the target comes back, and each finding replays alone 3 of 3. Bug 13 needs one
// address and one quantity: the black-box mode must not find it (coverage mode does:
// tests/scripts/fuzz_coverage_multi_fault.sh).
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>

#include "fuzz_test_support.hpp"

namespace {

using mbstorm::test::run_mbstorm;
using mbstorm::test::Target;
using mbstorm::test::tool_path;

// The last planted bug falls at about 61 s on a quiet machine (bench/README.md);
// --max-findings ends the run there.
constexpr int kSeconds = 120;

// One root cause per planted bug (see the server's header comment for the numbers).
const std::set<std::string> kPlanted = {
    "crash:target-down/fc10",                                                             // 1
    "crash:target-down/fc0F",                                                             // 2
    "crash:target-down/fc17",                                                             // 3
    "crash:target-down/fc04",                                                             // 4
    "spec-deviation:read-after-write-mismatch(holding-registers)/fc16",                   // 5
    "spec-deviation:read-after-write-mismatch-other-connection(holding-registers)/fc06",  // 6
    "malformed-response:echo-differs",                                                    // 7
    "hang:stalls-other-connections(partial-frame)",                                       // 8
    "crash:target-down/capacity",                                                         // 9
    "spec-deviation:unmapped-address-answered-normally(holding_registers)",               // 10
    "malformed-response:read-data-size",                                                  // 11
    "hang:no-answer/fc10",                                                                // 12
};
// Planted, and out of the black-box mode's reach (1 in 2^27 for a guess).
const std::string kCoverageOnly = "crash:target-down/fc01";  // 13
// Not planted, and a fault all the same: like libmodbus, the device drops what was pipelined
// behind a request it answered with 01 or 03 (its flush).
const std::string kFlush = "hang:drops-requests-after-exception";

TEST(SparseFault, EveryPlantedBugOnceEveryCrashACrashEveryFindingReplays) {
    Target device({tool_path("sparse_device_server"), "--port", "0", "--respawn",
                   "--restart-delay-ms", "20", "--exit-after-s", "400"});
    const std::string line = device.wait_for_line("PORT ");
    ASSERT_FALSE(line.empty()) << "sparse_device_server did not start";
    const std::string target = "127.0.0.1:" + line.substr(5);
    const std::string dir = mbstorm::test::temp_dir("sparse-fault");
    const auto run =
        run_mbstorm("fuzz --target " + target + " --seed 1 --seconds " + std::to_string(kSeconds) +
                        " --max-findings " + std::to_string(kPlanted.size() + 1) + " -q --out " +
                        dir + "/findings --json " + dir + "/summary.json",
                    kSeconds + 60);
    ASSERT_EQ(run.exit_code, 1) << run.output;
    std::ifstream in(dir + "/summary.json");
    const auto s = nlohmann::json::parse(in, nullptr, false);
    ASSERT_FALSE(s.is_discarded()) << run.output;
    // The map, learned: it starts at 1000 and has a hole.
    const auto& holding = s.at("model").at("tables").at("holding-registers").at("ranges");
    EXPECT_EQ(holding, nlohmann::json::parse("[[1000, 1039], [1060, 1099]]")) << run.output;
    EXPECT_TRUE(s.at("death_watch").get<bool>());
    std::map<std::string, int> found;
    for (const auto& f : s.at("findings")) {
        const std::string key = f.at("root_cause").get<std::string>();
        ++found[key];
        EXPECT_TRUE(kPlanted.count(key) || key == kFlush) << "not planted: " << f.dump(2);
        EXPECT_LE(f.at("restarts").get<unsigned>(), 3u) << f.dump(2);
        EXPECT_TRUE(f.at("confirmed").get<bool>()) << f.dump(2);
        // Alone, on a fresh connection, to the (restarted if need be) target: 3 of 3.
        const auto replay = run_mbstorm(
            "replay " + f.at("folder").get<std::string>() + " --target " + target + " --runs 3",
            90);
        EXPECT_EQ(replay.exit_code, 1) << key << "\n" << replay.output;
        EXPECT_NE(replay.output.find("3 of 3 run(s) reproduced"), std::string::npos)
            << key << "\n"
            << replay.output;
    }
    for (const std::string& bug : kPlanted) EXPECT_EQ(found[bug], 1) << bug << "\n" << run.output;
    EXPECT_LE(found[kFlush], 1);
    EXPECT_EQ(found[kCoverageOnly], 0);
    EXPECT_EQ(s.at("stop_reason"),
              "finding limit reached (--max-findings " + std::to_string(kPlanted.size() + 1) + ")")
        << run.output;
    std::filesystem::remove_all(dir);
}

}  // namespace
