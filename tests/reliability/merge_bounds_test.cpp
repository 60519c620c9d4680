// `mbstorm merge` given the files of two real shards with one number edited (issue #31 item 2):
// before, each of these made it allocate until it died (std::bad_alloc, exit 134) or print a
// wrapped number as a result. Now the runs merge, or are refused with the file and field named
// and exit code 2. Each merge runs under a 2 GB memory limit (its address space; its resident
// size for an ASan build, whose shadow memory reserves terabytes), so that a regression dies
// of bad_alloc instead of taking the machine.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "../server/client_test_support.hpp"
#include "../support/run_mbstorm.hpp"
#include "../support/sanitizers.hpp"
#include "server/server.hpp"

namespace mbstorm {
namespace {

using testing::HasSubstr;
namespace fs = std::filesystem;

using test::kAddressSanitizer;

// The memory bound: an address space of 2 GB (ulimit -v), or, for a binary built with ASan,
// whose shadow memory alone reserves terabytes of it, a resident size of 2 GB (ASan's own limit).
std::string memory_limit() {
    if (!kAddressSanitizer) return "ulimit -v 2097152; ";
    const char* options = std::getenv("ASAN_OPTIONS");
    return "export ASAN_OPTIONS='" +
           (options != nullptr && *options != '\0' ? std::string(options) + ":" : std::string()) +
           "hard_rss_limit_mb=2048'; ";
}

// mbstorm ARGS under a 2 GB memory limit, stdout and stderr together.
test::CommandResult merge_limited(const std::string& args) {
    std::string cmd = "(" + memory_limit() + "exec timeout -k 10 120 ";
    cmd.append(MBSTORM_BINARY).append(" merge ").append(args).append(") 2>&1");
    test::CommandResult result;
    FILE* pipe = ::popen(cmd.c_str(), "r");
    if (pipe == nullptr) return result;
    std::array<char, 4096> buf{};
    std::size_t n;
    while ((n = std::fread(buf.data(), 1, buf.size(), pipe)) > 0)
        result.output.append(buf.data(), n);
    const int status = ::pclose(pipe);
    result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return result;
}

class MergeBounds : public testing::Test {
  protected:
    // Two 1-s shards of one test against one in-process slave, run once for every test.
    static void SetUpTestSuite() {
        dir_ = fs::temp_directory_path() / ("mbstorm_merge_bounds_" + std::to_string(::getpid()));
        fs::remove_all(dir_);
        fs::create_directories(dir_);
        server::Server slave(test::test_config());
        const Error error = slave.start();
        ASSERT_TRUE(error.ok()) << error.text();
        for (int i = 0; i < 2; ++i) {
            const std::string shard = dir_ / ("s" + std::to_string(i));
            const auto r = test::run_mbstorm(
                "run --target 127.0.0.1:" + std::to_string(slave.port()) +
                    " -d 1s -c 2 --depth 2 -q --test-id bounds --shard " + std::to_string(i) +
                    "/2 --json " + shard + ".json --hlog " + shard + ".hlog",
                60);
            ASSERT_EQ(r.exit_code, 0) << r.output;
        }
    }
    static void TearDownTestSuite() { fs::remove_all(dir_); }

    // Copies the shards to a directory of their own, edits the JSONs given (and, when
    // log_shard_count is set, the shard count the logs' first lines name), and merges them.
    static test::CommandResult merge_edited(const std::string& name, std::vector<int> edited,
                                            const std::function<void(nlohmann::json&)>& edit,
                                            const std::string& log_shard_count = "") {
        const fs::path to = dir_ / name;
        fs::create_directories(to);
        std::string args;
        for (int i = 0; i < 2; ++i) {
            const std::string base = "s" + std::to_string(i);
            std::ifstream log(dir_ / (base + ".hlog"));
            std::string first_line;
            std::getline(log, first_line);
            if (const auto at = first_line.rfind("/2]");
                !log_shard_count.empty() && at != std::string::npos)
                first_line.replace(at, 3, "/" + log_shard_count + "]");
            std::ofstream(to / (base + ".hlog")) << first_line << '\n' << log.rdbuf();
            nlohmann::json doc = nlohmann::json::parse(std::ifstream(dir_ / (base + ".json")));
            if (std::find(edited.begin(), edited.end(), i) != edited.end()) edit(doc);
            std::ofstream(to / (base + ".json")) << doc.dump();
            args.append(" ")
                .append(to / (base + ".json"))
                .append(" ")
                .append(to / (base + ".hlog"));
        }
        return merge_limited(args);
    }

    static fs::path dir_;
};

fs::path MergeBounds::dir_;

TEST_F(MergeBounds, TheRealShardsMerge) {
    const auto r = merge_edited("real", {}, [](nlohmann::json&) {});
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_THAT(r.output, HasSubstr("2 runs of test 'bounds'"));
}

// Before: 86,400 empty intervals of a 270 KB histogram each, bad_alloc.
TEST_F(MergeBounds, ShardsADayApartMergeWithTheOverlapWarning) {
    const auto r = merge_edited("day", {1}, [](nlohmann::json& doc) {
        doc["test"]["measure_start_epoch_s"] =
            doc["test"]["measure_start_epoch_s"].get<double>() + 86'400.0;
    });
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_THAT(r.output, HasSubstr("did not all run at the same time"));
}

// Before: a slot of 1 µs, a million intervals a second, bad_alloc.
TEST_F(MergeBounds, AMicrosecondIntervalIsRefused) {
    const auto r = merge_edited("interval", {0, 1},
                                [](nlohmann::json& doc) { doc["timeline"]["interval_s"] = 1e-6; });
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_THAT(r.output, HasSubstr("s0.json: not a run's JSON summary mbstorm merge can read: "
                                    "interval_s is 1e-06"));
}

// Before: the missing shards listed one by one, two billion of them, bad_alloc.
TEST_F(MergeBounds, TwoBillionShardsAreRefused) {
    const auto r = merge_edited(
        "shards", {0, 1}, [](nlohmann::json& doc) { doc["test"]["shard_count"] = 2'000'000'000; },
        "2000000000");
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_THAT(r.output, HasSubstr("shard_count 2000000000 is not one run --shard makes"));
}

// Before: merged, exit 0, "duration 2562047h47m" and 0 tx/s.
TEST_F(MergeBounds, ADurationOf1e300SecondsIsRefused) {
    const auto r = merge_edited(
        "duration", {1}, [](nlohmann::json& doc) { doc["run"]["measured_duration_s"] = 1e300; });
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_THAT(r.output, HasSubstr("measured_duration_s is 1e+300"));
}

}  // namespace
}  // namespace mbstorm
