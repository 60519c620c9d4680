// Steady state allocates nothing: counts every operator new in this test binary while a
// pipelined load runs against an in-process server.
#include <gtest/gtest.h>

#include <vector>

#include "../support/counting_allocator.hpp"
#include "client_test_support.hpp"
#include "server/server.hpp"

using namespace mbstorm;

TEST(ZeroAlloc, SteadyStatePipelinedLoadAllocatesNothing) {
    auto config = test::test_config();
    server::Server srv(config);
    ASSERT_TRUE(srv.start().ok());
    constexpr int kDepth = 64;
    constexpr int kConns = 4;
    std::vector<test::Client> clients;
    for (int i = 0; i < kConns; ++i) clients.emplace_back(srv);
    std::vector<std::uint8_t> requests;
    for (int i = 0; i < kDepth; ++i) {
        auto r = test::read_holding(static_cast<std::uint16_t>(i), 1, 0, 10);
        requests.insert(requests.end(), r.begin(), r.end());
    }
    std::vector<std::uint8_t> responses(kDepth * test::read_holding_response_size(10));
    auto round = [&]() {
        bool ok = true;
        for (auto& c : clients) ok &= c.send_all(requests.data(), requests.size());
        for (auto& c : clients) ok &= c.recv_exact(responses.data(), responses.size());
        return ok;
    };
    for (int i = 0; i < 200; ++i) ASSERT_TRUE(round());  // warm-up: pools reach their size
    const std::uint64_t before = mbstorm::testing::allocations();
    bool ok = true;
    for (int i = 0; i < 2000 && ok; ++i) ok = round();
    const std::uint64_t after = mbstorm::testing::allocations();
    ASSERT_TRUE(ok);
    EXPECT_EQ(after - before, 0u) << "allocations during " << 2000 * kDepth * kConns
                                  << " transactions";
    EXPECT_GE(srv.stats().transactions, 2200u * kDepth * kConns);
}
