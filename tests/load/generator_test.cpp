#include "load/operation_generator.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <map>
#include <vector>

#include "codec/mbap.hpp"
#include "codec/pdu.hpp"
#include "load/zipf.hpp"

namespace mbstorm::load {
namespace {

Operation read_op(std::uint16_t first, std::uint16_t last, std::uint16_t quantity,
                  AddressMode mode = AddressMode::Sequential) {
    Operation op;
    op.function = 0x03;
    op.first_address = first;
    op.last_address = last;
    op.quantity = quantity;
    op.address_mode = mode;
    return op;
}

// Decodes a generated ADU back into a request, checking the MBAP header on the way.
codec::Request decode(const std::array<std::uint8_t, 260>& buf, std::size_t size, std::uint16_t tid,
                      std::uint8_t unit) {
    codec::TcpFrame frame;
    EXPECT_EQ(codec::decode_tcp_frame(codec::Bytes(buf.data(), size), frame),
              codec::CodecError::Ok);
    EXPECT_EQ(frame.header.transaction_id, tid);
    EXPECT_EQ(frame.header.unit_id, unit);
    codec::Request req;
    EXPECT_TRUE(codec::decode_request(frame.pdu, req).ok());
    return req;
}

TEST(Generator, SequentialTilesTheRangeAndWraps) {
    std::vector<Operation> ops{read_op(10, 31, 5)};
    OperationGenerator gen(ops, 1);
    std::array<std::uint8_t, 260> buf{};
    RequestInfo info;
    std::vector<std::uint16_t> starts;
    for (int i = 0; i < 10; ++i) {
        const std::size_t n = gen.next(static_cast<std::uint16_t>(i), buf, info);
        ASSERT_EQ(n, 12u);
        const codec::Request req = decode(buf, n, static_cast<std::uint16_t>(i), 1);
        EXPECT_EQ(req.address, info.address);
        EXPECT_EQ(req.quantity, 5);
        EXPECT_LE(info.address + 5 - 1, 31);
        starts.push_back(info.address);
    }
    EXPECT_EQ(starts, (std::vector<std::uint16_t>{10, 15, 20, 25, 10, 15, 20, 25, 10, 15}));
}

TEST(Generator, FixedStartWhenNoRangeGiven) {
    Operation op = read_op(100, 0, 3);
    op.last_address.reset();
    std::vector<Operation> ops{op};
    OperationGenerator gen(ops, 1);
    std::array<std::uint8_t, 260> buf{};
    RequestInfo info;
    for (int i = 0; i < 5; ++i) {
        gen.next(1, buf, info);
        EXPECT_EQ(info.address, 100);
    }
}

TEST(Generator, UniformCoversTheRangeEvenly) {
    std::vector<Operation> ops{read_op(1000, 1009, 1, AddressMode::Uniform)};
    OperationGenerator gen(ops, 7);
    std::array<std::uint8_t, 260> buf{};
    RequestInfo info;
    std::map<std::uint16_t, int> hits;
    constexpr int kSamples = 100000;
    for (int i = 0; i < kSamples; ++i) {
        gen.next(0, buf, info);
        ASSERT_GE(info.address, 1000);
        ASSERT_LE(info.address, 1009);
        ++hits[info.address];
    }
    ASSERT_EQ(hits.size(), 10u);
    for (const auto& [addr, count] : hits) {
        EXPECT_NEAR(count, kSamples / 10, kSamples / 100) << addr;  // within 10% of the mean
    }
}

TEST(Generator, ZipfIsSkewedTowardsTheFirstAddress) {
    // exponent 1 over 100 positions: P(rank k) = 1 / (k * H_100), H_100 = 5.18738.
    std::vector<Operation> ops{read_op(500, 599, 1, AddressMode::Zipf)};
    OperationGenerator gen(ops, 11);
    std::array<std::uint8_t, 260> buf{};
    RequestInfo info;
    std::vector<int> hits(100, 0);
    constexpr int kSamples = 200000;
    for (int i = 0; i < kSamples; ++i) {
        gen.next(0, buf, info);
        ASSERT_GE(info.address, 500);
        ASSERT_LE(info.address, 599);
        ++hits[info.address - 500];
    }
    const double h100 = 5.18738;
    for (int k : {1, 2, 3, 10}) {
        const double expected = kSamples / (k * h100);
        EXPECT_NEAR(hits[k - 1], expected, expected * 0.05) << "rank " << k;
    }
    EXPECT_NEAR(static_cast<double>(hits[0]) / hits[1], 2.0, 0.1);
}

TEST(Zipf, HigherExponentMeansMoreSkewAndRanksStayInRange) {
    Rng rng(3);
    ZipfSampler mild(65536, 0.5), steep(65536, 2.0);
    int mild_first = 0, steep_first = 0;
    for (int i = 0; i < 50000; ++i) {
        const auto a = mild.sample(rng), b = steep.sample(rng);
        ASSERT_GE(a, 1u);
        ASSERT_LE(a, 65536u);
        ASSERT_GE(b, 1u);
        ASSERT_LE(b, 65536u);
        mild_first += a == 1;
        steep_first += b == 1;
    }
    // exponent 2: P(1) = 1 / zeta(2) ~ 0.608.
    EXPECT_NEAR(steep_first / 50000.0, 0.608, 0.02);
    EXPECT_LT(mild_first, steep_first / 5);
}

TEST(Generator, PicksOperationsByWeight) {
    std::vector<Operation> ops{read_op(0, 9, 1), read_op(0, 9, 1)};
    ops[0].weight = 3;
    ops[1].weight = 1;
    ops[1].function = 0x04;
    OperationGenerator gen(ops, 5);
    std::array<std::uint8_t, 260> buf{};
    RequestInfo info;
    int first = 0;
    constexpr int kSamples = 40000;
    for (int i = 0; i < kSamples; ++i) {
        gen.next(0, buf, info);
        if (info.op_index == 0) {
            ++first;
            EXPECT_EQ(info.function, 0x03);
        } else {
            EXPECT_EQ(info.function, 0x04);
        }
    }
    EXPECT_NEAR(first, kSamples * 3 / 4, kSamples / 50);
}

TEST(Generator, WriteValuesCounterAndPattern) {
    Operation regs;
    regs.function = 0x10;
    regs.first_address = 7;
    regs.quantity = 3;
    regs.values.mode = ValueMode::Counter;
    regs.values.value = 65534;
    Operation coil;
    coil.function = 0x05;
    coil.first_address = 2;
    coil.values.mode = ValueMode::Pattern;
    coil.values.pattern = {1, 0};
    std::vector<Operation> ops{regs};
    OperationGenerator gen(ops, 1);
    std::array<std::uint8_t, 260> buf{};
    RequestInfo info;
    std::size_t n = gen.next(0xFFFF, buf, info);
    codec::Request req = decode(buf, n, 0xFFFF, 1);
    ASSERT_EQ(req.payload.size(), 6u);
    EXPECT_EQ(codec::load_be16(&req.payload[0]), 65534);
    EXPECT_EQ(codec::load_be16(&req.payload[2]), 65535);
    EXPECT_EQ(codec::load_be16(&req.payload[4]), 0);  // counter wraps

    std::vector<Operation> coils{coil};
    OperationGenerator coil_gen(coils, 1);
    for (std::uint16_t expected :
         {std::uint16_t{0xFF00}, std::uint16_t{0x0000}, std::uint16_t{0xFF00}}) {
        n = coil_gen.next(3, buf, info);
        req = decode(buf, n, 3, 1);
        EXPECT_EQ(req.function, 0x05);
        EXPECT_EQ(req.value, expected);
        EXPECT_EQ(info.value, expected);
    }
}

TEST(Generator, EveryGeneratableFunctionEncodesAValidRequest) {
    for (std::uint8_t fc : {0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07, 0x08, 0x0B, 0x0C, 0x0F, 0x10,
                            0x11, 0x16, 0x17, 0x18, 0x2B}) {
        Operation op;
        op.function = fc;
        op.unit_id = 9;
        op.first_address = 40;
        op.last_address = 200;
        op.quantity = (fc == 0x05 || fc == 0x06 || fc == 0x16) ? 1 : 17;
        op.write_quantity = 4;
        op.values.mode = ValueMode::Random;
        std::vector<Operation> ops{op};
        OperationGenerator gen(ops, fc);
        std::array<std::uint8_t, 260> buf{};
        RequestInfo info;
        const std::size_t n = gen.next(0x1234, buf, info);
        ASSERT_GT(n, 7u) << int(fc);
        EXPECT_LE(n, max_request_size(op)) << int(fc);
        const codec::Request req = decode(buf, n, 0x1234, 9);
        EXPECT_EQ(req.function, fc);
    }
}

TEST(Generator, SameSeedSameSequence) {
    std::vector<Operation> ops{read_op(0, 999, 1, AddressMode::Uniform)};
    OperationGenerator a(ops, 42), b(ops, 42), c(ops, 43);
    std::array<std::uint8_t, 260> buf{};
    RequestInfo ia, ib, ic;
    int differ = 0;
    for (int i = 0; i < 100; ++i) {
        a.next(0, buf, ia);
        b.next(0, buf, ib);
        c.next(0, buf, ic);
        EXPECT_EQ(ia.address, ib.address);
        differ += ia.address != ic.address;
    }
    EXPECT_GT(differ, 50);
}

TEST(Generator, RefusesABufferThatIsTooSmall) {
    std::vector<Operation> ops{read_op(0, 9, 1)};
    OperationGenerator gen(ops, 1);
    std::array<std::uint8_t, 11> small{};
    RequestInfo info;
    EXPECT_EQ(gen.next(0, small, info), 0u);
}

}  // namespace
}  // namespace mbstorm::load
