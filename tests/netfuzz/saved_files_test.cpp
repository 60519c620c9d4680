// finding.json as replay reads it back: every number must fit its field or the file is
// refused with the field named. A float or an out-of-range value converted into a narrower
// field would be undefined behaviour (UBSan: float-cast-overflow).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "netfuzz/finding.hpp"

using namespace mbstorm::netfuzz;
using mbstorm::Error;
using mbstorm::ErrorCode;
using mbstorm::Result;

namespace {

std::string seed_finding() {
    return std::string(MBSTORM_SOURCE_DIR) + "/fuzz/corpus/saved_finding/split-close.json";
}

}  // namespace

TEST(SavedFinding, EveryNumberMustFitItsField) {
    std::ifstream in(seed_finding());
    ASSERT_TRUE(in) << seed_finding();
    const nlohmann::json good = nlohmann::json::parse(in);
    const std::string path = (std::filesystem::temp_directory_path() /
                              ("mbstorm-finding-" + std::to_string(::getpid()) + ".json"))
                                 .string();
    auto load = [&](const nlohmann::json& j) {
        std::ofstream(path) << j.dump();
        return load_finding(path).error();
    };
    ASSERT_TRUE(load(good).ok()) << load(good).text();
    // A finding whose fault has no function code is saved with -1: that loads.
    nlohmann::json no_function = good;
    no_function["function"] = -1;
    EXPECT_TRUE(load(no_function).ok()) << load(no_function).text();
    struct Bad {
        nlohmann::json::json_pointer where;
        nlohmann::json value;
        const char* field;
    };
    const Bad bad[] = {
        {nlohmann::json::json_pointer("/timeout_ms"), 1e300, "timeout_ms"},
        {nlohmann::json::json_pointer("/timeout_ms"), -5, "timeout_ms"},
        {nlohmann::json::json_pointer("/function"), 300, "function"},
        {nlohmann::json::json_pointer("/profile/unit"), 256, "unit"},
        {nlohmann::json::json_pointer("/profile/unit"), 1.5, "unit"},
        {nlohmann::json::json_pointer("/state_range/1"), 0x20000, "state_range"},
        {nlohmann::json::json_pointer("/case/steps/0/conn"), 1e12, "conn"},
        {nlohmann::json::json_pointer("/case/steps/0/delay_us"), -1, "delay_us"},
        {nlohmann::json::json_pointer("/hits"), "many", "hits"},
        {nlohmann::json::json_pointer("/profile/unmapped/0/0"), 70000, "unmapped"},
    };
    for (const Bad& b : bad) {
        nlohmann::json j = good;
        j[b.where] = b.value;
        const Error error = load(j);
        EXPECT_EQ(error.code(), ErrorCode::InvalidInput) << b.where.to_string();
        EXPECT_EQ(error.place(), path) << error.text();
        EXPECT_NE(error.message().find(b.field), std::string::npos)
            << b.where.to_string() << ": " << error.text();
    }
    std::filesystem::remove(path);
}

// What replay judges with is what the run judged with: every flag of the target's profile
// that changes a verdict comes back from finding.json (a finding saved without the target's
// drop-after-exception policy replayed a frame of the wrong length answered 03 as a lost
// stream: 0 of 3 on sparse_device_server).
TEST(SavedFinding, TheProfileTheVerdictDependsOnComesBack) {
    Finding f;
    f.verdict = Verdict{Oracle::Hang, "drops-requests-after-exception", 0x17, "s", "e", "x"};
    f.fuzz_case.steps = {Step{Op::Send, 0, 0, 0, {0, 1, 0, 0, 0, 6, 1, 3, 0, 0, 0, 1}}};
    f.profile.probe_pdu = {0x03, 0, 0, 0, 1};
    f.profile.drops_after_exception = true;
    f.profile.refuses_length_mismatch = true;
    f.profile.one_connection = true;
    f.profile.answers_protocol_id = true;
    f.profile.marker_address = 1000;
    f.profile.unmapped[3] = {999, 1040};
    const auto dir = (std::filesystem::temp_directory_path() /
                      ("mbstorm-finding-profile-" + std::to_string(::getpid())))
                         .string();
    ASSERT_TRUE(save_finding(f, dir).ok());
    const Result<Finding> loaded = load_finding(dir);
    ASSERT_TRUE(loaded.ok()) << loaded.error().text();
    const Finding& g = *loaded;
    EXPECT_TRUE(g.profile.drops_after_exception);
    EXPECT_TRUE(g.profile.refuses_length_mismatch);
    EXPECT_TRUE(g.profile.one_connection);
    EXPECT_TRUE(g.profile.answers_protocol_id);
    EXPECT_EQ(g.profile.marker_address, 1000);
    EXPECT_EQ(g.profile.unmapped[3], (std::vector<std::uint16_t>{999, 1040}));
    std::filesystem::remove_all(dir);
}

// replay and the fuzz harness tell a finding that is not there from one that is not a finding.
TEST(SavedFinding, AMissingFindingIsNotFound) {
    const Error error = load_finding("/nonexistent/mbstorm-finding").error();
    EXPECT_EQ(error.code(), ErrorCode::NotFound) << error.text();
    EXPECT_EQ(error.text(), "cannot read /nonexistent/mbstorm-finding");
}
