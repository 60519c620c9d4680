// More connections than the open-files limit allows, on both sides: with io_uring direct
// descriptors the sockets are slots of each ring's table, not descriptors, so `mbstorm run`
// and `mbstorm serve` limited to 256 descriptors still hold 1000 connections between them.
// On epoll they are descriptors, and a run says so before it starts.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "child_process.hpp"
#include "net/features.hpp"

namespace mbstorm {
namespace {

using test::ChildProcess;
using testing::ContainsRegex;
using testing::HasSubstr;

constexpr rlim_t kNofile = 256;

TEST(DirectDescriptors, ThousandConnectionsBothSidesUnderA256DescriptorLimit) {
    if (!net::features().direct_descriptors)
        GTEST_SKIP() << "the kernel has no io_uring direct descriptors";
    ChildProcess serve(
        {"serve", "--listen", "127.0.0.1:0", "--threads", "8", "--max-connections", "1000"},
        kNofile);
    const std::string marker = "listening on 127.0.0.1:";
    ASSERT_TRUE(serve.wait_for_output(marker)) << serve.output();
    ASSERT_TRUE(serve.wait_for_output(" (")) << serve.output();
    const auto port = std::stoi(serve.output().substr(serve.output().find(marker) + marker.size()));
    EXPECT_THAT(serve.output(), HasSubstr("direct descriptors"));

    const auto dir =
        std::filesystem::temp_directory_path() / ("mbstorm-direct-" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    const std::string json_path = (dir / "r.json").string();
    // No --threads: the engine takes as many rings as 1000 connections need at 256 a table.
    ChildProcess run(
        {"run", "--target", "127.0.0.1:" + std::to_string(port), "-c", "1000", "--depth", "1", "-d",
         "2s", "--connect-timeout", "5s", "-q", "--json", json_path},
        kNofile);
    ASSERT_EQ(run.wait(60000), 0) << run.output();
    std::stringstream json;
    json << std::ifstream(json_path).rdbuf();
    EXPECT_THAT(json.str(), ContainsRegex("\"peak_open\": *1000\\b")) << json.str();
    EXPECT_THAT(json.str(), ContainsRegex("\"opened\": *1000\\b"));
    EXPECT_THAT(json.str(), ContainsRegex("\"failed\": *0\\b"));
    EXPECT_THAT(json.str(), ContainsRegex("\"closed_by_peer\": *0\\b"));
    EXPECT_THAT(json.str(), ContainsRegex("\"errors\": *0\\b"));
    EXPECT_THAT(json.str(), ContainsRegex("\"ok\": *[1-9]"));
    serve.signal(SIGTERM);
    EXPECT_EQ(serve.wait(10000), 0) << serve.output();
    // The server saw every connection and refused or evicted none.
    EXPECT_THAT(serve.output(), HasSubstr("connections: 1000 total"));
    EXPECT_THAT(serve.output(), HasSubstr("0 evicted, 0 refused, 0 accepts out of fds"));
    std::filesystem::remove_all(dir);
}

// On epoll every connection is a descriptor: a plan that needs more than the limit allows is
// refused before a socket opens, saying why, rather than failing connects half-way.
TEST(DirectDescriptors, OnEpollARunNeedingMoreDescriptorsThanTheLimitSaysSoBeforeItStarts) {
    ChildProcess run({"run", "--backend", "epoll", "--target", "127.0.0.1:1", "-c", "1000",
                      "--depth", "1", "-d", "1s", "-q"},
                     kNofile);
    EXPECT_EQ(run.wait(20000), 2) << run.output();
    EXPECT_THAT(run.output(), HasSubstr("open-files limit"));
    EXPECT_THAT(run.output(), HasSubstr("the epoll backend holds each connection as a descriptor"));
}

}  // namespace
}  // namespace mbstorm
