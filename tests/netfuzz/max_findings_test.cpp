// `fuzz --max-findings N`: the campaign ends once N root causes are saved (the last one still
// confirmed, minimised and written out), long before --seconds, and every summary says why it
// stopped.
#include <gtest/gtest.h>

#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>

#include "fuzz_test_support.hpp"

namespace {

using mbstorm::test::run_mbstorm;

// Far more than the first bugs of multi_fault_server take (about a second, seed 1): a run that
// ignored the limit would use all of it and find most of the eleven bugs the black-box mode
// reaches.
constexpr int kSeconds = 60;

TEST(MaxFindings, TheRunEndsAtTheNthFindingLongBeforeTheDeadline) {
    mbstorm::test::Target* raw = nullptr;
    const std::string target = mbstorm::test::start_broken(raw, "multi_fault_server");
    std::unique_ptr<mbstorm::test::Target> server(raw);
    ASSERT_FALSE(target.empty()) << "multi_fault_server did not start";
    // 1: "stop at the first finding"; 3: the third (with seed 1, a crash: restarted and
    // confirmed before the run ends).
    for (const unsigned limit : {1u, 3u}) {
        SCOPED_TRACE(limit);
        const std::string dir = mbstorm::test::temp_dir("max-findings");
        const std::string reason =
            "finding limit reached (--max-findings " + std::to_string(limit) + ")";
        const auto run = run_mbstorm("fuzz --target " + target + " --seed 1 --seconds " +
                                         std::to_string(kSeconds) + " --max-findings " +
                                         std::to_string(limit) + " --timeout 300ms -q --out " +
                                         dir + "/findings --json " + dir + "/summary.json",
                                     kSeconds + 30);
        EXPECT_EQ(run.exit_code, 1) << run.output;  // findings: exit 1, as without the limit
        EXPECT_NE(run.output.find("stopped: " + reason), std::string::npos) << run.output;
        std::ifstream in(dir + "/summary.json");
        const auto s = nlohmann::json::parse(in, nullptr, false);
        ASSERT_FALSE(s.is_discarded()) << run.output;
        EXPECT_EQ(s.at("stop_reason"), reason) << s.dump(2);
        ASSERT_EQ(s.at("findings").size(), limit) << run.output;
        EXPECT_LT(s.at("seconds").get<double>(), kSeconds / 2.0) << run.output;
        // The finding that reached the limit is whole: confirmed, saved, not cut short.
        const auto& last = s.at("findings").back();
        EXPECT_TRUE(last.at("confirmed").get<bool>()) << last.dump(2);
        EXPECT_EQ(last.at("minimize_note"), "") << last.dump(2);
        EXPECT_TRUE(
            std::filesystem::exists(last.at("folder").get<std::string>() + "/finding.json"));
        EXPECT_EQ(s.at("findings_not_minimized"), 0) << s.dump(2);
        std::filesystem::remove_all(dir);
    }
}

TEST(MaxFindings, NegativeOrGarbageValuesAreUsageErrors) {
    for (const char* bad : {"-1", "abc", "1.5", "2x", "''"}) {
        const auto run =
            run_mbstorm(std::string("fuzz --target 127.0.0.1:1 --seconds 1 --max-findings ") + bad);
        EXPECT_EQ(run.exit_code, 2) << bad << "\n" << run.output;
        EXPECT_NE(run.output.find("--max-findings: "), std::string::npos) << bad << run.output;
        EXPECT_NE(run.output.find("is not a whole number"), std::string::npos) << bad << run.output;
        EXPECT_EQ(run.output.find("WARNING: writes"), std::string::npos) << bad << run.output;
    }
}

}  // namespace
