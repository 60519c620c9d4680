// Data model pieces on their own: packed bit tables against a reference, read counters, FIFOs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <random>
#include <thread>
#include <vector>

#include "codec/bytes.hpp"
#include "slave/data_model.hpp"

namespace mbstorm::slave {
namespace {

TEST(BitTable, PackedReadsAndWritesMatchAReference) {
    constexpr std::uint32_t kSize = 1000;
    BitTable table(kSize);
    std::vector<bool> ref(kSize, false);
    std::mt19937 rng(3);
    for (int round = 0; round < 2000; ++round) {
        const auto quantity = static_cast<std::uint16_t>(1 + rng() % 300);
        const auto address = static_cast<std::uint16_t>(rng() % (kSize - quantity + 1));
        if (rng() % 2) {
            std::vector<std::uint8_t> in((quantity + 7) / 8);
            for (auto& b : in) b = static_cast<std::uint8_t>(rng());
            table.write_packed(address, quantity, in.data());
            for (std::uint32_t i = 0; i < quantity; ++i)
                ref[address + i] = (in[i / 8] >> (i % 8)) & 1;
        } else {
            // One guard byte after the packed bytes: must stay untouched.
            std::vector<std::uint8_t> out((quantity + 7) / 8 + 1, 0xA5);
            table.read_packed(address, quantity, out.data());
            ASSERT_EQ(out.back(), 0xA5);
            for (std::uint32_t i = 0; i < out.size() * 8 - 8; ++i) {
                const bool want = i < quantity && ref[address + i];
                ASSERT_EQ(((out[i / 8] >> (i % 8)) & 1) != 0, want) << address << "+" << i;
            }
        }
    }
    for (std::uint16_t i = 0; i < kSize; ++i) ASSERT_EQ(table.get(i), ref[i]) << i;
}

TEST(BitTable, LastAddressOfAFullTable) {
    BitTable table(kFullTable);
    table.set(65535, true);
    std::uint8_t out[2] = {0, 0};
    table.read_packed(65535, 1, out);
    EXPECT_EQ(out[0], 1);
    const std::uint8_t in[1] = {0x00};
    table.write_packed(65535, 1, in);
    EXPECT_FALSE(table.get(65535));
}

TEST(BitTable, ConcurrentWritersOfOneWordLoseNoBits) {
    BitTable table(64);
    std::vector<std::thread> threads;
    for (unsigned t = 0; t < 4; ++t) {
        threads.emplace_back([&, t] {
            // Thread t owns bits 16t..16t+15 of the same word; it toggles them many times and
            // leaves them set.
            std::uint8_t on[2] = {0xFF, 0xFF}, off[2] = {0, 0};
            for (int i = 0; i < 5000; ++i) {
                table.write_packed(static_cast<std::uint16_t>(16 * t), 16, off);
                table.write_packed(static_cast<std::uint16_t>(16 * t), 16, on);
                table.set(static_cast<std::uint16_t>(16 * t + 3), false);
                table.set(static_cast<std::uint16_t>(16 * t + 3), true);
            }
        });
    }
    for (auto& t : threads) t.join();
    for (std::uint16_t i = 0; i < 64; ++i) EXPECT_TRUE(table.get(i)) << i;
}

TEST(RegisterTable, ReadCountersBumpOnlyWhenCovered) {
    RegisterTable table(100);
    table.add_read_counter(10, 1);
    table.add_read_counter(20, 5);
    std::uint8_t out[200];
    table.read_be(0, 10, out);  // covers neither
    EXPECT_EQ(table.get(10), 0);
    table.read_be(10, 11, out);  // covers both
    EXPECT_EQ(codec::load_be16(out), 1);
    EXPECT_EQ(codec::load_be16(out + 20), 5);
    table.read_be(20, 1, out);
    EXPECT_EQ(codec::load_be16(out), 10);
    EXPECT_THROW(table.add_read_counter(100, 1), std::out_of_range);
}

TEST(RegisterTable, ValuesReadTheSameThroughEveryAccessor) {
    // The table keeps wire byte order (issue #18): get/set/add/mask_write see host values,
    // read_be/write_be the bytes of the wire, for every quantity the copy unrolls (1-9).
    RegisterTable table(64);
    for (std::uint16_t a = 0; a < 16; ++a)
        table.set(a, static_cast<std::uint16_t>(0x0102 * (a + 1)));
    for (std::uint16_t quantity = 1; quantity <= 9; ++quantity) {
        std::uint8_t out[32] = {};
        table.read_be(3, quantity, out);
        for (std::uint16_t i = 0; i < quantity; ++i)
            ASSERT_EQ(codec::load_be16(out + 2 * i), table.get(static_cast<std::uint16_t>(3 + i)))
                << quantity << " " << i;
        EXPECT_EQ(out[2 * quantity], 0) << "wrote past the quantity " << quantity;
    }
    const std::uint8_t in[] = {0xAB, 0xCD, 0x00, 0x01};
    table.write_be(40, 2, in);
    EXPECT_EQ(table.get(40), 0xABCD);
    EXPECT_EQ(table.get(41), 0x0001);
    table.set(50, 0xFFFF);
    EXPECT_EQ(table.add(50, 2), 0x0001);  // modulo 2^16
    EXPECT_EQ(table.get(50), 0x0001);
    EXPECT_EQ(table.add(50, 0x00FF), 0x0100);  // the carry crosses the byte boundary
    EXPECT_EQ(table.mask_write(40, 0x00F2, 0x0025), (0xABCD & 0x00F2) | (0x0025 & ~0x00F2));
    EXPECT_EQ(table.get(40), (0xABCD & 0x00F2) | (0x0025 & ~0x00F2));
}

TEST(RegisterTable, ReadsAndWritesMatchAReferenceAcrossWordBoundaries) {
    // Registers are packed four to a 64-bit word (issue #18): every start lane, every length
    // that crosses zero to several word boundaries, up to the table's last register (sizes
    // with and without a partial last word), and nothing written outside the range.
    for (std::uint32_t size : {1u, 3u, 4u, 62u, 64u, 65536u}) {
        RegisterTable table(size);
        std::vector<std::uint16_t> ref(size);
        std::mt19937 rng(size);
        for (int round = 0; round < 3000; ++round) {
            const std::uint32_t quantity = 1 + rng() % std::min<std::uint32_t>(size, 125);
            const std::uint32_t address = rng() % (size - quantity + 1);
            SCOPED_TRACE(testing::Message()
                         << "size " << size << " address " << address << " quantity " << quantity);
            if (round % 3 == 0) {
                std::uint8_t in[250];
                for (std::uint32_t i = 0; i < quantity; ++i) {
                    ref[address + i] = static_cast<std::uint16_t>(rng());
                    codec::store_be16(in + 2 * i, ref[address + i]);
                }
                table.write_be(static_cast<std::uint16_t>(address),
                               static_cast<std::uint16_t>(quantity), in);
            } else if (round % 3 == 1) {
                const auto a = static_cast<std::uint16_t>(address);
                ref[a] = static_cast<std::uint16_t>(rng());
                table.set(a, ref[a]);
            }
            std::uint8_t out[4 + 250 + 4];
            std::memset(out, 0xEE, sizeof out);
            table.read_be(static_cast<std::uint16_t>(address), static_cast<std::uint16_t>(quantity),
                          out + 4);
            for (std::uint32_t i = 0; i < quantity; ++i)
                ASSERT_EQ(codec::load_be16(out + 4 + 2 * i), ref[address + i]) << i;
            for (std::uint32_t i = 0; i < 4; ++i) {
                ASSERT_EQ(out[i], 0xEE) << "wrote before the range";
                ASSERT_EQ(out[4 + 2 * quantity + i], 0xEE) << "wrote past the range";
            }
            // By whole words: the same bytes, and at most kWordSlack bytes either side touched.
            constexpr std::size_t kGuard = RegisterTable::kWordSlack + 2;
            std::uint8_t words[kGuard + 250 + kGuard];
            std::memset(words, 0xEE, sizeof words);
            table.read_be_words(static_cast<std::uint16_t>(address),
                                static_cast<std::uint16_t>(quantity), words + kGuard);
            ASSERT_EQ(std::memcmp(words + kGuard, out + 4, 2 * quantity), 0);
            for (std::uint32_t i = 0; i < 2; ++i) {
                ASSERT_EQ(words[i], 0xEE) << "more than the slack before";
                ASSERT_EQ(words[kGuard + 2 * quantity + RegisterTable::kWordSlack + i], 0xEE)
                    << "more than the slack after";
            }
            const auto probe = static_cast<std::uint16_t>(rng() % size);
            ASSERT_EQ(table.get(probe), ref[probe]) << probe;
        }
    }
}

TEST(RegisterTable, WritersOfNeighboursInOneWordLoseNothing) {
    // Four registers share a word: a write to one is a compare-and-swap that must keep the
    // concurrent writes to the other three.
    RegisterTable table(8);
    constexpr int kIterations = 20'000;
    std::vector<std::thread> threads;
    for (unsigned t = 0; t < 4; ++t) {
        threads.emplace_back([&, t] {
            const auto own = static_cast<std::uint16_t>(2 + t);  // straddles words 0 and 1
            for (int i = 0; i < kIterations; ++i) {
                table.add(own, 1);
                table.set(own, static_cast<std::uint16_t>(table.get(own) + 1));
                table.mask_write(own, 0xFFFF, 0);  // unchanged
            }
        });
    }
    for (auto& t : threads) t.join();
    for (std::uint16_t a = 2; a < 6; ++a) EXPECT_EQ(table.get(a), 2 * kIterations) << a;
    EXPECT_EQ(table.get(0), 0);
    EXPECT_EQ(table.get(7), 0);
}

TEST(DataModel, FifoHelpersRespectLimits) {
    ModelConfig c;
    c.sizes.holding_registers = 10;
    DataModel m(c);
    const std::uint16_t too_long[9] = {};
    EXPECT_FALSE(m.fifo_set(1, too_long));  // needs 10 registers from address 1
    EXPECT_TRUE(m.fifo_set(1, std::span(too_long, 8)));
    EXPECT_EQ(m.holding_registers().get(1), 8);
    EXPECT_FALSE(m.fifo_push(1, 5));  // would need register 10
    EXPECT_FALSE(m.fifo_push(10, 5));
}

}  // namespace
}  // namespace mbstorm::slave
