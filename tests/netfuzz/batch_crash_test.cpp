// A target that crashes during a pipelined batch and never comes back (no --restart-cmd): the
// suspects cannot be re-run alone, so the batch itself is reported as one unconfirmed crash
// finding whose reproducer resends every frame of the batch in order, and it replays.
#include <gtest/gtest.h>

#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>

#include "fuzz_test_support.hpp"
#include "netfuzz/finding.hpp"
#include "netfuzz/generator.hpp"
#include "netfuzz/minimize.hpp"

namespace {

using mbstorm::test::CommandResult;
using mbstorm::test::run_mbstorm;
using mbstorm::test::start_crash_server;
using mbstorm::test::Target;
using mbstorm::test::tool_path;
namespace nf = mbstorm::netfuzz;

// Runs are bounded from outside too: a stuck fuzzer or replay fails (exit 124) instead of
// blocking the suite.
constexpr int kRunLimitSeconds = 120;
constexpr std::uint64_t kSeed = 7;
// Cases per round of the campaign loop with the default 4 connections (4 lanes x 48).
constexpr std::size_t kCasesPerRound = 4 * 48;

CommandResult run_bounded(const std::string& args) {
    return run_mbstorm(args, kRunLimitSeconds);
}

nlohmann::json read_json(const std::string& path) {
    std::ifstream in(path);
    return nlohmann::json::parse(in, nullptr, false);
}

std::string read_text(const std::string& path) {
    std::ifstream in(path);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// The pipelined frames of the round that starts after `cases_before` cases, as the campaign
// builds it: same seed, every case pipelinable (--transport-share 0), nothing deprioritised
// before the crash. One entry per MBAP frame, in order.
std::vector<std::vector<std::uint8_t>> batch_frames(std::uint64_t cases_before) {
    nf::GeneratorOptions options;
    options.seed = kSeed;
    options.isolated_per_mille = 0;
    nf::Generator gen(options);
    nf::Case c;
    for (std::uint64_t i = 0; i < cases_before; ++i) gen.next(c);
    nf::Case all;
    for (std::size_t i = 0; i < kCasesPerRound; ++i) {
        gen.next(c);
        if (!c.pipelinable) continue;
        all.steps.insert(all.steps.end(), c.steps.begin(), c.steps.end());
    }
    std::vector<std::vector<std::uint8_t>> frames;
    for (const nf::Step& s : nf::split_frames(all).steps) frames.push_back(s.bytes);
    return frames;
}

bool is_zero_quantity_fc0f(const std::vector<std::uint8_t>& frame) {
    return frame.size() >= 12 && frame[7] == 0x0F && frame[10] == 0 && frame[11] == 0;
}

TEST(BatchCrash, LostTargetAfterPipelinedCrashIsReportedAsUnconfirmedBatchFinding) {
    int port = 0;
    auto server = start_crash_server(port, 0);
    ASSERT_TRUE(server) << "broken_server_crash did not start on any port";
    const std::string dir = mbstorm::test::temp_dir("batch-crash");
    // Every case pipelined (--transport-share 0): the planted crash can only hit in a batch.
    const auto run = run_bounded("fuzz --target 127.0.0.1:" + std::to_string(port) + " --seed " +
                                 std::to_string(kSeed) +
                                 " --transport-share 0 --no-model --timeout 300ms --cases 1000000 "
                                 "--seconds 60 -q --restart-wait 1s --out " +
                                 dir + "/findings --json " + dir + "/summary.json --junit " + dir +
                                 "/fuzz.xml --sarif " + dir + "/fuzz.sarif");
    // Documented: exit 1 for findings (and for a target that never came back).
    ASSERT_EQ(run.exit_code, 1) << run.output;
    const auto s = read_json(dir + "/summary.json");
    ASSERT_FALSE(s.is_discarded()) << run.output;
    EXPECT_TRUE(s.at("target_lost").get<bool>()) << run.output;
    EXPECT_EQ(s.at("restarts"), 0);
    ASSERT_EQ(s.at("findings").size(), 1u) << s.dump(2);
    const auto& f = s.at("findings")[0];
    EXPECT_EQ(f.at("oracle"), "crash") << f.dump(2);
    EXPECT_FALSE(f.at("confirmed").get<bool>()) << f.dump(2);
    EXPECT_FALSE(f.at("minimized").get<bool>()) << f.dump(2);
    const std::string note = f.at("note").get<std::string>();
    EXPECT_NE(note.find("pipelined batch"), std::string::npos) << note;
    EXPECT_NE(note.find("not minimised"), std::string::npos) << note;
    EXPECT_NE(run.output.find("note: " + note), std::string::npos) << run.output;

    // The reproducer: one send per frame of the batch, in the batch's order, on one connection.
    const std::string folder = f.at("folder").get<std::string>();
    ASSERT_FALSE(folder.empty());
    const auto saved = read_json(folder + "/finding.json");
    ASSERT_FALSE(saved.is_discarded());
    EXPECT_EQ(saved.at("oracle"), "crash");
    EXPECT_FALSE(saved.at("confirmed").get<bool>());
    EXPECT_EQ(saved.at("note"), note);
    // case_number is the batch's first case, counted from 1 after the first looks (cases
    // discovery suggested, run alone before anything the generator makes).
    const auto expected = batch_frames(f.at("case_number").get<std::uint64_t>() - 1 -
                                       s.at("first_looks").get<std::uint64_t>());
    const auto& steps = saved.at("case").at("steps");
    ASSERT_EQ(steps.size(), expected.size());
    ASSERT_GT(expected.size(), 1u);
    bool has_planted = false;
    for (std::size_t i = 0; i < steps.size(); ++i) {
        std::vector<std::uint8_t> bytes;
        ASSERT_TRUE(nf::from_hex(steps[i].at("hex").get<std::string>(), bytes));
        EXPECT_EQ(steps[i].at("op"), "send");
        EXPECT_EQ(steps[i].at("conn"), 0);
        EXPECT_EQ(bytes, expected[i]) << "frame " << i;
        has_planted |= is_zero_quantity_fc0f(bytes);
    }
    EXPECT_TRUE(has_planted) << "the batch does not hold the planted FC0F quantity-0 frame";
    EXPECT_NE(f.at("summary").get<std::string>().find(std::to_string(steps.size()) + " frames"),
              std::string::npos)
        << f.dump(2);

    // JUnit and SARIF show it like any other finding.
    const std::string junit = read_text(dir + "/fuzz.xml");
    EXPECT_NE(junit.find("type=\"crash\""), std::string::npos) << junit;
    EXPECT_NE(junit.find("pipelined batch"), std::string::npos) << junit;
    const auto sarif = read_json(dir + "/fuzz.sarif");
    ASSERT_FALSE(sarif.is_discarded());
    const auto& results = sarif.at("runs")[0].at("results");
    ASSERT_EQ(results.size(), 1u);
    EXPECT_EQ(results[0].at("ruleId"), "crash");
    EXPECT_FALSE(results[0].at("properties").at("confirmed").get<bool>());
    server.reset();

    // Replaying the batch against a fresh server crashes it again.
    int replay_port = 0;
    auto fresh = start_crash_server(replay_port, 1);
    ASSERT_TRUE(fresh) << "broken_server_crash did not start on any port";
    const auto replay =
        run_bounded("replay " + folder + " --target 127.0.0.1:" + std::to_string(replay_port));
    EXPECT_EQ(replay.exit_code, 1) << replay.output;  // documented: 1 = reproduces
    EXPECT_NE(replay.output.find("REPRODUCES"), std::string::npos) << replay.output;
    EXPECT_NE(replay.output.find("1 of 1 run(s) reproduced"), std::string::npos) << replay.output;
    fresh.reset();
    std::filesystem::remove_all(dir);
}

}  // namespace
