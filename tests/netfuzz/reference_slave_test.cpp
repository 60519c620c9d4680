// End to end against the reference slave (`mbstorm serve`): no false positives, reproducible
// with a seed, and the CLI's safety rules and exit codes.
#include <gtest/gtest.h>

#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "fuzz_test_support.hpp"
#include "netfuzz/case.hpp"
#include "netfuzz/cross_transport.hpp"

namespace {

using mbstorm::netfuzz::MutationClass;
using mbstorm::test::run_mbstorm;

std::string start_reference(std::unique_ptr<mbstorm::test::Target>& server) {
    server = std::make_unique<mbstorm::test::Target>(
        std::vector<std::string>{MBSTORM_BINARY, "serve", "--listen", "127.0.0.1:0", "--threads",
                                 "2", "--duration", "120s"});
    const std::string line = server->wait_for_line("listening on ");
    const auto at = line.find("listening on ");
    if (at == std::string::npos) return {};
    const auto rest = line.substr(at + 13);
    return rest.substr(0, rest.find(' '));
}

// 15 s gives about 1.9 million cases on a quiet 2-core machine (the least run class but the
// first looks about 750 times).
TEST(FuzzReferenceSlave, FifteenSecondsWithoutFindings) {
    std::unique_ptr<mbstorm::test::Target> server;
    const std::string target = start_reference(server);
    ASSERT_FALSE(target.empty());
    const std::string dir = mbstorm::test::temp_dir("reference");
    const auto run = run_mbstorm("fuzz --target " + target + " --seconds 15 --seed 3 -q --out " +
                                 dir + " --json " + dir + "/s.json --junit " + dir +
                                 "/j.xml --sarif " + dir + "/r.sarif");
    EXPECT_EQ(run.exit_code, 0) << run.output;
    EXPECT_NE(run.output.find("no findings"), std::string::npos) << run.output;
    std::ifstream in(dir + "/s.json");
    const auto summary = nlohmann::json::parse(in);
    EXPECT_TRUE(summary.at("findings").empty());
    // Every mutation class that speaks MBAP over plain TCP ran (the device model aims two of
    // them at the learned map): all but naive bytes, RTU/ASCII framing, TLS to a plain
    // port's other direction, and coverage mutations (black-box run: no corpus). No count of
    // cases: that is speed, and bench/'s business.
    std::set<std::string> expected;
    for (std::size_t i = 0; i < static_cast<std::size_t>(MutationClass::Count); ++i) {
        const auto k = static_cast<MutationClass>(i);
        const bool framing_only = k == MutationClass::BadChecksum ||
                                  k == MutationClass::BrokenSilence ||
                                  k == MutationClass::NoSilence || k == MutationClass::Noise;
        // Repeated: asked only of a target whose silences do not repeat.
        if (k == MutationClass::NaiveRandom || k == MutationClass::CoverageMutation ||
            k == MutationClass::Repeated || framing_only)
            continue;
        if (mbstorm::netfuzz::is_cross_transport(k) && k != MutationClass::TlsToPlain) continue;
        expected.insert(std::string(mbstorm::netfuzz::class_name(k)));
    }
    std::set<std::string> ran;
    for (const auto& [name, count] : summary.at("cases_by_class").items())
        if (count.get<std::uint64_t>() > 0) ran.insert(name);
    EXPECT_EQ(ran, expected) << summary.dump();
    std::ifstream sarif(dir + "/r.sarif");
    const auto s = nlohmann::json::parse(sarif);
    EXPECT_EQ(s.at("version"), "2.1.0");
    EXPECT_TRUE(s.at("runs").at(0).at("results").empty());
    EXPECT_TRUE(std::filesystem::exists(dir + "/j.xml"));
    std::filesystem::remove_all(dir);
}

TEST(FuzzReferenceSlave, SameSeedSameCases) {
    std::unique_ptr<mbstorm::test::Target> server;
    const std::string target = start_reference(server);
    ASSERT_FALSE(target.empty());
    const std::string dir = mbstorm::test::temp_dir("seed");
    nlohmann::json a, b;
    for (auto* out : {&a, &b}) {
        const auto run = run_mbstorm("fuzz --target " + target +
                                     " --cases 3000 --seed 11 -q --json " + dir + "/s.json");
        ASSERT_EQ(run.exit_code, 0) << run.output;
        std::ifstream in(dir + "/s.json");
        *out = nlohmann::json::parse(in);
    }
    EXPECT_EQ(a.at("cases"), 3000);
    EXPECT_EQ(a.at("cases_by_class"), b.at("cases_by_class"));
    std::filesystem::remove_all(dir);
}

TEST(FuzzCli, FirstLineWarnsAboutWrites) {
    std::unique_ptr<mbstorm::test::Target> server;
    const std::string target = start_reference(server);
    ASSERT_FALSE(target.empty());
    const auto run = run_mbstorm("fuzz --target " + target +
                                 " --cases 200 -q --out /tmp/mbstorm-netfuzz-unused");
    EXPECT_EQ(run.exit_code, 0) << run.output;
    EXPECT_EQ(run.output.rfind("mbstorm fuzz: WARNING: writes will be sent to " + target, 0), 0u)
        << run.output;
}

TEST(FuzzCli, UsageErrorsExitTwo) {
    EXPECT_EQ(run_mbstorm("fuzz --seconds 1").exit_code, 2);                     // no --target
    EXPECT_EQ(run_mbstorm("fuzz --target 127.0.0.1:1").exit_code, 2);            // no bound
    const auto remote = run_mbstorm("fuzz --target 192.0.2.1:502 --seconds 1");  // TEST-NET-1
    EXPECT_EQ(remote.exit_code, 2);
    EXPECT_NE(remote.output.find("--allow-remote"), std::string::npos) << remote.output;
    EXPECT_EQ(run_mbstorm("fuzz --target 127.0.0.1:1 --seconds 1 --timeout 200ms").exit_code,
              2);  // refused
    EXPECT_EQ(run_mbstorm("replay /nonexistent --target 127.0.0.1:1").exit_code, 2);
    EXPECT_EQ(run_mbstorm("replay /tmp --target 192.0.2.1:502").exit_code, 2);
}

}  // namespace
