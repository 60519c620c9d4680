// `mbstorm fuzz --restart-cmd`: after the planted crash in tests/tools/broken_server_crash.cpp
// the fuzzer runs the restart command, waits for the target to answer again and fuzzes on;
// a restart command that does not bring the target back ends the run with a clear reason.
#include <gtest/gtest.h>
#include <sys/prctl.h>

#include <cerrno>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>

#include "fuzz_test_support.hpp"

namespace {

using mbstorm::test::CommandResult;
using mbstorm::test::run_mbstorm;
using mbstorm::test::start_crash_server;
using mbstorm::test::Target;
using mbstorm::test::tool_path;

// Every run is bounded from outside too: a fuzzer stuck in the restart path fails the test
// (exit 124 from timeout(1)) instead of blocking the suite.
constexpr int kRestartRunLimitSeconds = 180;
// Servers started by a restart command end by themselves even if this test dies first.
constexpr int kRestartServerLifetimeSeconds = 300;
// Cases per round of the campaign loop with the default 4 connections (4 lanes x 48).
constexpr std::uint64_t kRestartCasesPerRound = 4 * 48;

CommandResult run_mbstorm_bounded(const std::string& args) {
    return run_mbstorm(args, kRestartRunLimitSeconds);
}

using mbstorm::test::RestartedServers;

const nlohmann::json* find_crash(const nlohmann::json& summary) {
    for (const auto& f : summary.at("findings"))
        if (f.at("oracle") == "crash" && f.at("function") == 0x0F) return &f;
    return nullptr;
}

// One broken_server_crash to fuzz, a scratch folder, and whatever the restart command starts.
class RestartCmd : public ::testing::Test {
  protected:
    void SetUp() override {
        first_ = start_crash_server(port_, 0, kRestartServerLifetimeSeconds);
        ASSERT_TRUE(first_) << "broken_server_crash did not start on any port";
        dir_ = mbstorm::test::temp_dir("restart-cmd");
        restarted_ = std::make_unique<RestartedServers>(dir_ + "/restarted.pids");
    }
    void TearDown() override {
        if (restarted_) {
            EXPECT_TRUE(restarted_->stop_all()) << "a restarted server survived";
        }
        restarted_.reset();
        first_.reset();
        if (!dir_.empty()) std::filesystem::remove_all(dir_);
    }
    // The restart command: broken_server_crash again on the same port, after `delay` (shell
    // sleep syntax) when given, in the background with no tie to the fuzzer's output so that
    // the test's pipe from mbstorm closes when mbstorm exits.
    std::string restart_cmd(const std::string& delay = "") const {
        std::string cmd = delay.empty() ? "" : "sleep " + delay + "; ";
        return cmd + server_cmd() + " </dev/null >/dev/null 2>&1 &";
    }
    // The same server run in the foreground: the command never returns while it serves.
    std::string foreground_restart_cmd() const {
        return "exec " + server_cmd() + " </dev/null >/dev/null 2>&1";
    }
    std::string server_cmd() const {
        return tool_path("broken_server_crash") + " --port " + std::to_string(port_) +
               " --pid-file " + dir_ + "/restarted.pids --exit-after-s " +
               std::to_string(kRestartServerLifetimeSeconds);
    }
    // Fuzzes the server with a fixed seed; `extra` adds the bounds and restart options.
    CommandResult fuzz(const std::string& extra) const {
        return run_mbstorm_bounded("fuzz --target 127.0.0.1:" + std::to_string(port_) +
                                   " --seed 7 --timeout 300ms --out " + dir_ + "/findings --json " +
                                   dir_ + "/summary.json " + extra);
    }
    nlohmann::json summary() const {
        std::ifstream in(dir_ + "/summary.json");
        return nlohmann::json::parse(in);
    }

    int port_ = 0;
    std::unique_ptr<Target> first_;
    std::string dir_;
    std::unique_ptr<RestartedServers> restarted_;
};

// The one planted crash costs every restart of the run, at least one and at most the
// per-root-cause limit (3), and its finding says so.
void expect_restarts_charged_to(const nlohmann::json& crash, const nlohmann::json& s,
                                const std::string& output) {
    const auto total = s.at("restarts").get<std::uint64_t>();
    const auto charged = crash.at("restarts").get<std::uint64_t>();
    EXPECT_GE(charged, 1u) << output;
    EXPECT_LE(charged, 3u) << output;
    EXPECT_EQ(total, charged) << output;
}

TEST_F(RestartCmd, CrashedTargetIsRestartedAndFuzzingGoesOn) {
    const std::uint64_t cases = 60000;
    const auto run = fuzz("--cases " + std::to_string(cases) +
                          " --restart-wait 30s --restart-cmd '" + restart_cmd() + "'");
    // Documented: exit 1 when there are findings.
    ASSERT_EQ(run.exit_code, 1) << run.output;
    const auto s = summary();
    const nlohmann::json* crash = find_crash(s);
    ASSERT_NE(crash, nullptr) << "planted crash not found:\n" << run.output;
    expect_restarts_charged_to(*crash, s, run.output);
    EXPECT_NE(run.output.find("restart(s)"), std::string::npos) << run.output;
    EXPECT_FALSE(s.at("target_lost").get<bool>()) << run.output;
    // It went on to the full case budget, at least two whole rounds after the crash's round.
    EXPECT_EQ(s.at("stop_reason"), "case limit reached") << run.output;
    EXPECT_EQ(s.at("cases").get<std::uint64_t>(), cases);
    EXPECT_GT(cases - crash->at("case_number").get<std::uint64_t>(), 3 * kRestartCasesPerRound)
        << run.output;
    // The restart command really ran, and the server it started last is still serving.
    const auto pids = restarted_->pids();
    ASSERT_FALSE(pids.empty()) << run.output;
    EXPECT_EQ(::kill(pids.back(), 0), 0) << "the last restarted server is not running";
}

// The wait starts when the restart command returns: a command that takes longer than
// --restart-wait itself (as `systemctl restart` may) still gets the whole wait afterwards.
TEST_F(RestartCmd, SlowRestartCmdDoesNotUseUpTheWait) {
    const auto run =
        fuzz("--cases " + std::to_string(kRestartCasesPerRound) +
             " -q --no-minimize --restart-wait 2s --restart-cmd '" + restart_cmd("3") + "'");
    ASSERT_EQ(run.exit_code, 1) << run.output;
    const auto s = summary();
    ASSERT_NE(find_crash(s), nullptr) << run.output;
    EXPECT_FALSE(s.at("target_lost").get<bool>()) << run.output;
    expect_restarts_charged_to(*find_crash(s), s, run.output);
    EXPECT_EQ(s.at("stop_reason"), "case limit reached") << run.output;
}

// A command that runs the target in the foreground never returns: the fuzzer must not wait
// for it, only for the target to answer.
TEST_F(RestartCmd, ForegroundRestartCmdIsLeftRunningAndFuzzingGoesOn) {
    const auto run = fuzz("--cases " + std::to_string(3 * kRestartCasesPerRound) +
                          " -q --no-minimize --restart-wait 5s --restart-cmd '" +
                          foreground_restart_cmd() + "'");
    ASSERT_EQ(run.exit_code, 1) << run.output;
    const auto s = summary();
    ASSERT_NE(find_crash(s), nullptr) << run.output;
    EXPECT_FALSE(s.at("target_lost").get<bool>()) << run.output;
    expect_restarts_charged_to(*find_crash(s), s, run.output);
    EXPECT_EQ(s.at("stop_reason"), "case limit reached") << run.output;
    const auto pids = restarted_->pids();
    ASSERT_FALSE(pids.empty()) << run.output;
    EXPECT_EQ(::kill(pids.back(), 0), 0) << "the last restarted server is not running";
}

TEST_F(RestartCmd, RestartCmdThatDoesNotRestoreTargetEndsRunWithReason) {
    const auto run =
        fuzz("--cases 1000000 --seconds 120 -q --restart-wait 1s --restart-cmd 'true'");
    // Documented: exit 1 when the target never came back (124 would mean it hung).
    ASSERT_EQ(run.exit_code, 1) << run.output;
    const auto s = summary();
    EXPECT_TRUE(s.at("target_lost").get<bool>()) << run.output;
    EXPECT_EQ(s.at("restarts"), 0);
    const std::string reason = s.at("stop_reason").get<std::string>();
    EXPECT_NE(reason.find("did not come back within 1000 ms"), std::string::npos) << reason;
    EXPECT_NE(reason.find("--restart-wait"), std::string::npos) << reason;
    EXPECT_NE(reason.find("--restart-cmd 'true'"), std::string::npos) << reason;
    // The human-readable summary says the same.
    EXPECT_NE(run.output.find("stopped: " + reason), std::string::npos) << run.output;
    EXPECT_LT(s.at("cases").get<std::uint64_t>(), 1000000u) << "it did not stop early";
}

TEST_F(RestartCmd, NoRestartCmdAndNoRecoveryNamesTheMissingOption) {
    const auto run = fuzz("--cases 1000000 --seconds 120 -q --restart-wait 1s");
    ASSERT_EQ(run.exit_code, 1) << run.output;
    const auto s = summary();
    EXPECT_TRUE(s.at("target_lost").get<bool>()) << run.output;
    const std::string reason = s.at("stop_reason").get<std::string>();
    EXPECT_NE(reason.find("within 1000 ms"), std::string::npos) << reason;
    EXPECT_NE(reason.find("no --restart-cmd given"), std::string::npos) << reason;
}

}  // namespace
