// Every planted fault in tests/tools/broken_server_*.cpp is found with a fixed seed and a
// bounded number of cases, and `mbstorm replay` reproduces the saved finding.
#include <gtest/gtest.h>

#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>

#include "fuzz_test_support.hpp"

namespace {

using mbstorm::test::run_mbstorm;

struct Planted {
    const char* server;
    std::set<std::string> oracles;  // any of these
    std::set<int> functions;        // any of these (empty: any)
    std::set<std::string> classes;  // any of these (empty: any)
};

// A planted-fault server, fuzzed with a fixed seed: what the run printed and its JSON summary.
struct FuzzedServer {
    FuzzedServer(const char* name, const std::string& bounds) {
        mbstorm::test::Target* raw = nullptr;
        target = mbstorm::test::start_broken(raw, name);
        server.reset(raw);
        if (target.empty()) return;
        dir = mbstorm::test::temp_dir(name);
        run = run_mbstorm("fuzz --target " + target + " --seed 7 " + bounds +
                          " --timeout 300ms --out " + dir + "/findings --json " + dir +
                          "/summary.json");
        std::ifstream in(dir + "/summary.json");
        summary = nlohmann::json::parse(in, nullptr, false);
    }
    ~FuzzedServer() {
        if (!dir.empty()) std::filesystem::remove_all(dir);
    }
    std::unique_ptr<mbstorm::test::Target> server;
    std::string target, dir;
    mbstorm::test::CommandResult run;
    nlohmann::json summary;
};

class BrokenTarget : public ::testing::TestWithParam<Planted> {};

TEST_P(BrokenTarget, PlantedFaultIsFoundAndReplays) {
    const Planted& p = GetParam();
    const FuzzedServer fuzzed(p.server, "--cases 20000 -q");
    ASSERT_FALSE(fuzzed.target.empty()) << p.server << " did not start";
    const auto& [target, run, summary] = std::tie(fuzzed.target, fuzzed.run, fuzzed.summary);
    ASSERT_EQ(run.exit_code, 1) << run.output;
    ASSERT_FALSE(summary.is_discarded()) << run.output;
    std::string folder;
    for (const auto& f : summary.at("findings")) {
        if (!p.oracles.count(f.at("oracle").get<std::string>())) continue;
        const int fc = f.at("function").is_number() ? f.at("function").get<int>() : -1;
        if (!p.functions.empty() && !p.functions.count(fc)) continue;
        if (!p.classes.empty() && !p.classes.count(f.at("class").get<std::string>())) continue;
        folder = f.at("folder").get<std::string>();
        break;
    }
    ASSERT_FALSE(folder.empty()) << "planted fault not found:\n" << run.output;
    EXPECT_TRUE(std::filesystem::exists(folder + "/finding.json"));
    EXPECT_TRUE(std::filesystem::exists(folder + "/traffic.txt"));
    // Replay: the same root cause, every time.
    const auto replay = run_mbstorm("replay " + folder + " --target " + target + " --runs 2");
    // Findings about delivery (a frame in pieces) replay as reliably as the rest: on this host
    // each piece goes out only once the server has read the one before.
    EXPECT_EQ(replay.exit_code, 1) << replay.output;
    EXPECT_NE(replay.output.find("2 of 2 run(s) reproduced"), std::string::npos) << replay.output;
}

INSTANTIATE_TEST_SUITE_P(
    PlantedFaults, BrokenTarget,
    ::testing::Values(Planted{"broken_server_crash", {"crash"}, {0x0F}, {}},
                      Planted{"broken_server_hang", {"hang"}, {0x2B}, {}},
                      Planted{"broken_server_exception", {"spec-deviation"}, {0x03, 0x04}, {}},
                      Planted{"broken_server_tid", {"malformed-response"}, {0x17}, {}},
                      // Every mutation that delivers a frame in pieces meets the
                      // planted bug: one root cause, found by whichever comes first.
                      Planted{"broken_server_split",
                              {"hang", "unexpected-close"},
                              {},
                              {"split", "partial-hold", "burst-split", "drip"}},
                      // Each piece goes out once the slow server has read the one before.
                      Planted{"broken_server_split_close",
                              {"unexpected-close"},
                              {},
                              {"split", "partial-hold", "burst-split", "drip"}},
                      Planted{"broken_server_protocol", {"spec-deviation"}, {}, {"protocol-id"}},
                      Planted{"broken_server_lostwrite",
                              {"spec-deviation"},
                              {0x10},
                              {"stateful-same", "stateful-cross"}}),
    [](const ::testing::TestParamInfo<Planted>& info) {
        return std::string(info.param.server).substr(14);
    });

}  // namespace

namespace {

// A target that frames by the MBAP length and closes on a request too short or too long for its
// function code (pymodbus 3.0 does): the close comes before anything follows the frame, so the
// stream was not lost. One root cause, whether the request was of the wrong length or
// well-framed and undecodable (a byte count that disagrees), not a lost stream besides.
TEST(RefusingTarget, ClosingOnARequestOfTheWrongLengthIsNotALostStream) {
    const FuzzedServer fuzzed("broken_server_refuse", "--cases 20000 -q");
    ASSERT_FALSE(fuzzed.target.empty()) << "broken_server_refuse did not start";
    ASSERT_EQ(fuzzed.run.exit_code, 1) << fuzzed.run.output;
    ASSERT_FALSE(fuzzed.summary.is_discarded()) << fuzzed.run.output;
    int refusals = 0;
    for (const auto& f : fuzzed.summary.at("findings")) {
        const std::string key = f.at("root_cause").get<std::string>();
        EXPECT_EQ(key.rfind("stream:", 0), std::string::npos) << f.dump(2);
        if (key == "unexpected-close:close-with-request-pending/invalid-request") ++refusals;
    }
    EXPECT_EQ(refusals, 1) << fuzzed.run.output;
}

// A handler that never reads its request (FC 14 answers everything with the same empty record
// list, as pymodbus 3.0's stub does): invalid requests answered normally (two checks it skips,
// 02 and 03 owed) and the valid request's undecodable answer are one defect, so one finding,
// the valid request's (field-level: a valid request in its place got the very same bytes).
TEST(StubTarget, AHandlerThatDoesNotReadItsRequestIsOneFinding) {
    const FuzzedServer fuzzed("broken_server_stub", "--cases 20000 -q");
    ASSERT_FALSE(fuzzed.target.empty()) << "broken_server_stub did not start";
    ASSERT_EQ(fuzzed.run.exit_code, 1) << fuzzed.run.output;
    ASSERT_FALSE(fuzzed.summary.is_discarded()) << fuzzed.run.output;
    std::vector<std::string> file_record;
    for (const auto& f : fuzzed.summary.at("findings"))
        if (f.at("function").is_number() && f.at("function").get<int>() == 0x14)
            file_record.push_back(f.at("root_cause").get<std::string>());
    ASSERT_EQ(file_record.size(), 1u) << fuzzed.run.output;
    EXPECT_EQ(file_record[0].rfind("malformed-response:", 0), 0u) << fuzzed.run.output;
}

// Field-level minimisation (issue #26 item 4): FC 10 never reads its byte count. The cases
// that show it carry other wrong fields too (a byte count and data that disagree with each
// other and with the quantity, a range past the end of the table, where the 02 it draws is the
// same skipped check). One finding, its reproducer wrong in one field only, replaying alone.
TEST(ByteCountTarget, AFindingNamesTheOneWrongFieldItNeeds) {
    const FuzzedServer fuzzed("broken_server_bytecount", "--cases 20000 -q");
    ASSERT_FALSE(fuzzed.target.empty()) << "broken_server_bytecount did not start";
    ASSERT_EQ(fuzzed.run.exit_code, 1) << fuzzed.run.output;
    ASSERT_FALSE(fuzzed.summary.is_discarded()) << fuzzed.run.output;
    const auto& findings = fuzzed.summary.at("findings");
    ASSERT_EQ(findings.size(), 1u) << fuzzed.run.output;
    const auto& f = findings[0];
    EXPECT_EQ(f.at("root_cause"), "spec-deviation:invalid-request-answered-normally(owes-03)/fc10")
        << fuzzed.run.output;
    const std::vector<std::string> wrong = f.at("wrong_fields");
    ASSERT_EQ(wrong.size(), 1u) << f.dump(2);
    EXPECT_TRUE(wrong[0] == "byte-count" || wrong[0] == "data-length") << f.dump(2);
    const std::string folder = f.at("folder");
    const auto replay =
        run_mbstorm("replay " + folder + " --target " + fuzzed.target + " --runs 2");
    EXPECT_NE(replay.output.find("2 of 2 run(s) reproduced"), std::string::npos) << replay.output;
}

// --baseline: an earlier run's findings are known. A run that finds only those exits 0 and
// says they are known (console, JSON, SARIF baselineState); one whose finding the baseline
// does not list fails as before. Its --sarif file is a baseline too; a file that is neither is
// a usage error before anything is sent.
TEST(Baseline, KnownFindingsDoNotFailTheRunNewOnesDo) {
    const FuzzedServer first("broken_server_exception", "--cases 20000 -q");
    ASSERT_FALSE(first.target.empty());
    ASSERT_EQ(first.run.exit_code, 1) << first.run.output;
    ASSERT_FALSE(first.summary.at("findings").empty());
    const std::string dir = mbstorm::test::temp_dir("baseline");
    const std::string known = dir + "/known.json", other = dir + "/other.json";
    std::ofstream(known) << first.summary.dump();
    nlohmann::json changed = first.summary;
    for (auto& f : changed.at("findings")) f["root_cause"] = "crash:target-down/fc42";
    std::ofstream(other) << changed.dump();

    const FuzzedServer again("broken_server_exception",
                             "--cases 20000 --baseline " + known + " --sarif " + dir + "/s.json");
    EXPECT_EQ(again.run.exit_code, 0) << again.run.output;
    EXPECT_NE(again.run.output.find("(known: in the baseline)"), std::string::npos);
    EXPECT_EQ(again.summary.at("baseline").at("new").get<int>(), 0) << again.summary.dump(2);
    for (const auto& f : again.summary.at("findings"))
        EXPECT_EQ(f.at("baseline").get<std::string>(), "known");
    std::ifstream sarif_in(dir + "/s.json");
    const auto sarif = nlohmann::json::parse(sarif_in, nullptr, false);
    ASSERT_FALSE(sarif.is_discarded());
    for (const auto& res : sarif.at("runs").at(0).at("results")) {
        EXPECT_EQ(res.at("baselineState").get<std::string>(), "unchanged");
        // What GitHub code scanning needs to show a result: a file and a line.
        const auto& where = res.at("locations").at(0).at("physicalLocation");
        EXPECT_FALSE(where.at("artifactLocation").at("uri").get<std::string>().empty());
        EXPECT_EQ(where.at("region").at("startLine").get<int>(), 1);
    }

    const FuzzedServer by_sarif("broken_server_exception",
                                "--cases 20000 -q --baseline " + dir + "/s.json");
    EXPECT_EQ(by_sarif.run.exit_code, 0) << by_sarif.run.output;

    const FuzzedServer unknown("broken_server_exception", "--cases 20000 -q --baseline " + other);
    EXPECT_EQ(unknown.run.exit_code, 1) << unknown.run.output;
    EXPECT_GT(unknown.summary.at("baseline").at("new").get<int>(), 0);
    EXPECT_EQ(unknown.summary.at("baseline").at("absent"),
              nlohmann::json::array({"crash:target-down/fc42"}));

    std::ofstream(dir + "/bad.json") << "{\"findings\": [{\"root_cause\": 7}]}";
    const auto bad =
        run_mbstorm("fuzz --target 127.0.0.1:1 --cases 10 --baseline " + dir + "/bad.json");
    EXPECT_EQ(bad.exit_code, 2) << bad.output;
    EXPECT_NE(bad.output.find("bad.json: a root cause is not a non-empty string"),
              std::string::npos)
        << bad.output;
    std::filesystem::remove_all(dir);
}

// A target the fuzzer cannot start on says why: a device answering every request with 04
// answers, so the message shows what it answered to each probe; a refused connect names the
// reason.
TEST(UnusableTarget, TheErrorSaysWhatTheTargetAnsweredOrWhyItCouldNotConnect) {
    const FuzzedServer failing("broken_server_failing", "--cases 100 -q");
    ASSERT_FALSE(failing.target.empty());
    EXPECT_EQ(failing.run.exit_code, 2) << failing.run.output;
    EXPECT_NE(failing.run.output.find("answers unit 1 but no read with a normal response"),
              std::string::npos)
        << failing.run.output;
    EXPECT_NE(failing.run.output.find("0x03: exception 04 (SERVER DEVICE FAILURE)"),
              std::string::npos)
        << failing.run.output;
    const auto refused = run_mbstorm("fuzz --target 127.0.0.1:1 --cases 10 -q");
    EXPECT_EQ(refused.exit_code, 2) << refused.output;
    EXPECT_NE(refused.output.find("cannot connect to the target: Connection refused"),
              std::string::npos)
        << refused.output;
}

// A target that answers 06 (busy) to most requests: the summary says most cases were wasted
// (the JSON counts them) and the fuzzer slowed down, instead of a bare "no findings". 1000
// cases (2 s) give about 1,900 pipelined answers, three quarters of them busy.
TEST(BusyTarget, WastedCasesAreReportedAndTheFuzzerSlowsDown) {
    const FuzzedServer fuzzed("broken_server_busy", "--cases 1000 --seconds 20");
    ASSERT_FALSE(fuzzed.target.empty()) << "broken_server_busy did not start";
    const auto& [run, summary] = std::tie(fuzzed.run, fuzzed.summary);
    ASSERT_FALSE(summary.is_discarded()) << run.output;
    const auto answers = summary.at("answers").get<std::uint64_t>();
    const auto busy = summary.at("busy_answers").get<std::uint64_t>();
    EXPECT_GT(answers, 16u) << run.output;
    EXPECT_GT(busy * 2, answers) << run.output;
    EXPECT_TRUE(summary.at("slowed_for_busy").get<bool>()) << run.output;
    EXPECT_NE(run.output.find("exception 06 (busy)"), std::string::npos) << run.output;
    // Busy is a legal answer to any request: it is never a finding by itself.
    for (const auto& f : summary.at("findings"))
        EXPECT_EQ(f.at("rule").get<std::string>().find("busy"), std::string::npos) << f.dump();
}

}  // namespace
