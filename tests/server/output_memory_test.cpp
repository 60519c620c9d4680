// Output memory is given back: blocks a crowd of slow readers needed return to the heap once no
// connection used them for a whole interval (issue #31 item 5: 140 MB stayed after 1,500
// non-reading clients left), while blocks a steady load keeps using stay pooled.
#include <gtest/gtest.h>

#include <chrono>
#include <memory>
#include <thread>
#include <vector>

#include "client_test_support.hpp"
#include "server/out_queue.hpp"
#include "server/server.hpp"

using namespace mbstorm;

TEST(BlockPool, TrimGivesBackOnlyWhatNoGetNeededSinceTheLastTrim) {
    server::BlockPool pool;
    pool.prewarm(4);
    std::vector<server::OutBlock*> crowd;
    for (int i = 0; i < 100; ++i) crowd.push_back(pool.get());
    for (server::OutBlock* b : crowd) pool.put(b);
    EXPECT_EQ(pool.allocated(), 100u);
    // The first trim only starts the interval: these blocks were used during the last one.
    EXPECT_EQ(pool.trim(10), 0u);
    // A steady user takes and returns 3 blocks: the 97 it never needed go, not below `keep`.
    for (int round = 0; round < 5; ++round) {
        server::OutBlock* a = pool.get();
        server::OutBlock* b = pool.get();
        server::OutBlock* c = pool.get();
        pool.put(a);
        pool.put(b);
        pool.put(c);
    }
    EXPECT_EQ(pool.trim(2), 97u);
    EXPECT_EQ(pool.allocated(), 3u);
    // A block in use is never given back; one used during the interval waits for the next.
    server::OutBlock* held = pool.get();
    EXPECT_EQ(pool.trim(0), 2u);
    EXPECT_EQ(pool.allocated(), 1u);
    EXPECT_EQ(pool.free_blocks(), 0u);
    pool.put(held);
    EXPECT_EQ(pool.trim(0), 0u);
    EXPECT_EQ(pool.trim(0), 1u);
    EXPECT_EQ(pool.allocated(), 0u);
}

TEST(OutputMemory, BlocksACrowdOfSlowReadersNeededAreGivenBackAfterTheyLeave) {
    auto config = test::test_config();
    server::Server srv(config);
    ASSERT_TRUE(srv.start().ok());
    const std::size_t kept = config.prealloc_output_blocks + 64;
    // 60 clients that never read, each asking for about 3 MB of answers: the server queues
    // up to its backpressure cap (64 KiB) on each, in blocks, beyond what the sockets hold.
    std::vector<std::uint8_t> requests;
    for (int i = 0; i < 12000; ++i) {
        auto r = test::read_holding(static_cast<std::uint16_t>(i), 1, 0, 125);
        requests.insert(requests.end(), r.begin(), r.end());
    }
    {
        std::vector<std::unique_ptr<test::Client>> crowd;
        for (int i = 0; i < 60; ++i) {
            crowd.push_back(std::make_unique<test::Client>(srv, "127.0.0.1", 4096));
            ASSERT_TRUE(crowd.back()->ok());
            crowd.back()->send_all(requests.data(), 16 * 1024);  // what fits before it stalls
        }
        ASSERT_TRUE(test::eventually([&] { return srv.stats().output_blocks > 2 * kept; }))
            << "peak " << srv.stats().output_blocks << " blocks";
    }
    // All gone: within a few trim intervals only the kept blocks remain allocated.
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(8);
    while (srv.stats().output_blocks_held > kept && std::chrono::steady_clock::now() < until)
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
    EXPECT_LE(srv.stats().output_blocks_held, kept)
        << "peak " << srv.stats().output_blocks << " blocks";
    EXPECT_GT(srv.stats().output_blocks, 2 * kept);
}
