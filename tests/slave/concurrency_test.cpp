// Several threads reading and writing one model through the handler: no torn values.
#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "slave_test_support.hpp"

namespace mbstorm::slave::test {
namespace {

// Writers store "stamped" values (high byte == low byte) so any mix of two writes, or of a
// write and the old value, would show up as a register whose bytes differ.
bool stamped(std::uint16_t v) {
    return (v >> 8) == (v & 0xFF);
}

TEST(Concurrency, RegistersAreNeverTorn) {
    DataModel m(small_config(64));
    constexpr int kWriters = 3, kReaders = 3, kIterations = 20'000;
    std::atomic<int> torn{0}, failed{0};
    std::vector<std::thread> threads;
    for (int w = 0; w < kWriters; ++w) {
        threads.emplace_back([&, w] {
            std::uint8_t out[kMinOutput];
            for (int i = 0; i < kIterations; ++i) {
                const unsigned b = static_cast<unsigned>((i * 7 + w * 31) & 0xFF);
                const unsigned v = b << 8 | b;
                std::vector<std::uint8_t> req;
                if (i % 3 == 0) {
                    req = Pdu(0x06).u16(static_cast<unsigned>(i % 64)).u16(v);
                } else if (i % 3 == 1) {
                    req = Pdu(0x10).u16(0).u16(10).u8(20).words({v, v, v, v, v, v, v, v, v, v});
                } else {
                    req = Pdu(0x16).u16(5).u16(0x0000).u16(v);  // AND 0: becomes the OR mask
                }
                if (handle_request(req, m, out).outcome != Outcome::Response) ++failed;
            }
        });
    }
    for (int r = 0; r < kReaders; ++r) {
        threads.emplace_back([&] {
            std::uint8_t out[kMinOutput];
            const std::vector<std::uint8_t> req = Pdu(0x03).u16(0).u16(64);
            for (int i = 0; i < kIterations; ++i) {
                const HandleResult res = handle_request(req, m, out);
                if (res.outcome != Outcome::Response || res.size != 2 + 128) {
                    ++failed;
                    continue;
                }
                for (int k = 0; k < 64; ++k) {
                    if (!stamped(codec::load_be16(out + 2 + 2 * k))) ++torn;
                }
            }
        });
    }
    for (auto& t : threads) t.join();
    EXPECT_EQ(failed.load(), 0);
    EXPECT_EQ(torn.load(), 0);
    EXPECT_EQ(m.diagnostics().message_count(),
              static_cast<std::uint16_t>((kWriters + kReaders) * kIterations));
}

TEST(Concurrency, ConcurrentMaskWritesLoseNoBits) {
    DataModel m(small_config(8));
    std::vector<std::thread> threads;
    // Each of 16 threads sets its own bit (AND all-ones except nothing, OR its bit) many times,
    // then clears nothing: the final value must have every bit set.
    for (unsigned bit = 0; bit < 16; ++bit) {
        threads.emplace_back([&, bit] {
            std::uint8_t out[kMinOutput];
            const std::vector<std::uint8_t> set =
                Pdu(0x16).u16(0).u16(0xFFFF & ~(1u << bit)).u16(1u << bit);
            const std::vector<std::uint8_t> clear =
                Pdu(0x16).u16(0).u16(0xFFFF & ~(1u << bit)).u16(0);
            for (int i = 0; i < 2000; ++i) {
                handle_request(clear, m, out);
                handle_request(set, m, out);
            }
        });
    }
    for (auto& t : threads) t.join();
    EXPECT_EQ(m.holding_registers().get(0), 0xFFFF);
}

TEST(Concurrency, CoilsAndCountersUnderLoad) {
    DataModel m(small_config(2000));
    m.input_registers().add_read_counter(7, 1);
    std::vector<std::thread> threads;
    constexpr int kThreads = 4, kReads = 5000;
    for (int t = 0; t < kThreads; ++t) {
        threads.emplace_back([&] {
            std::uint8_t out[kMinOutput];
            const std::vector<std::uint8_t> read = Pdu(0x04).u16(0).u16(10);
            const std::vector<std::uint8_t> coils =
                Pdu(0x0F).u16(0).u16(16).u8(2).u8(0xFF).u8(0xFF);
            for (int i = 0; i < kReads; ++i) {
                handle_request(read, m, out);
                handle_request(coils, m, out);
            }
        });
    }
    for (auto& t : threads) t.join();
    // Every read bumped the counter exactly once.
    EXPECT_EQ(m.input_registers().get(7), static_cast<std::uint16_t>(kThreads * kReads));
    EXPECT_TRUE(m.coils().get(15));
}

}  // namespace
}  // namespace mbstorm::slave::test
