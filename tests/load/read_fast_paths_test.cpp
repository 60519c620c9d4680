// The engine writes FC01-04 requests in place and accepts their expected answers without the
// general decoder (OperationGenerator::encode_read, check_response's read_data_as_expected).
// These check both against the checked codec, byte for byte and outcome for outcome.
#include <gtest/gtest.h>

#include <array>
#include <vector>

#include "codec/mbap.hpp"
#include "codec/pdu.hpp"
#include "load/operation_generator.hpp"
#include "load/response_check.hpp"

namespace mbstorm::load {
namespace {

using stats::Outcome;

TEST(ReadFastPaths, GeneratedReadsAreTheCheckedEncodersBytes) {
    for (std::uint8_t fc : {0x01, 0x02, 0x03, 0x04}) {
        for (std::uint16_t quantity : {1, 7, 8, 125, 2000}) {
            if (fc >= 0x03 && quantity > 125) continue;
            Operation op;
            op.function = fc;
            op.unit_id = 0x2A;
            op.first_address = 0xFF00;
            op.last_address = 0xFFFF;
            op.quantity = quantity;
            if (std::uint32_t{op.first_address} + quantity > 0x10000)
                op.first_address = static_cast<std::uint16_t>(0x10000 - quantity);
            std::vector<Operation> ops{op};
            OperationGenerator gen(ops, 7);
            for (std::uint16_t tid : {0x0000, 0x1234, 0xFFFF}) {
                std::array<std::uint8_t, 260> got{};
                RequestInfo info;
                const std::size_t n = gen.next(tid, got, info);
                ASSERT_EQ(n, 12u);
                std::array<std::uint8_t, 260> want{};
                const codec::EncodeResult pdu = codec::encode_read_request(
                    fc, info.address, quantity, codec::MutableBytes(want.data() + 7, 253));
                ASSERT_TRUE(pdu.ok());
                const codec::EncodeResult adu = codec::encode_tcp_frame(
                    tid, op.unit_id, codec::Bytes(want.data() + 7, pdu.size), want);
                ASSERT_EQ(adu.size, n);
                EXPECT_TRUE(std::equal(got.begin(), got.begin() + 12, want.begin()));
                EXPECT_EQ(info.function, fc);
                EXPECT_EQ(info.unit_id, op.unit_id);
                EXPECT_EQ(info.quantity, quantity);
                EXPECT_EQ(info.op_index, 0);
                EXPECT_GE(info.address, op.first_address);
                EXPECT_EQ(info.answer_bytes, fc <= 0x02 ? (quantity + 7) / 8 : 2 * quantity);
            }
        }
    }
}

TEST(ReadFastPaths, GeneratedReadsNeedTheirWholeSize) {
    Operation op;
    op.function = 0x03;
    op.quantity = 10;
    std::vector<Operation> ops{op};
    OperationGenerator gen(ops, 1);
    std::array<std::uint8_t, 11> small{};
    RequestInfo info;
    EXPECT_EQ(gen.next(1, small, info), 0u);
}

codec::TcpFrame frame_of(std::uint8_t unit, const std::vector<std::uint8_t>& pdu) {
    codec::TcpFrame f;
    f.header.unit_id = unit;
    f.pdu = codec::Bytes(pdu.data(), pdu.size());
    return f;
}

TEST(ReadFastPaths, AnswersAreJudgedAsTheFullCheckJudgesThem) {
    RequestInfo regs;
    regs.function = 0x03;
    regs.unit_id = 1;
    regs.quantity = 2;
    RequestInfo bits = regs;
    bits.function = 0x01;
    bits.quantity = 9;  // 2 data bytes
    struct Case {
        const RequestInfo* request;
        std::vector<std::uint8_t> pdu;
        Outcome outcome;
    };
    const std::vector<Case> cases = {
        {&regs, {0x03, 0x04, 0xAA, 0xBB, 0xCC, 0xDD}, Outcome::Ok},
        {&regs, {0x03, 0x02, 0xAA, 0xBB}, Outcome::Malformed},        // one register short
        {&regs, {0x03, 0x04, 0xAA, 0xBB, 0xCC}, Outcome::Malformed},  // byte count lies
        {&regs, {0x03, 0x03, 0xAA, 0xBB, 0xCC}, Outcome::Malformed},  // odd byte count
        {&regs, {0x83, 0x02}, Outcome::Exception},
        {&regs, {0x04, 0x04, 0xAA, 0xBB, 0xCC, 0xDD}, Outcome::WrongFunction},
        {&bits, {0x01, 0x02, 0xFF, 0x01}, Outcome::Ok},
        {&bits, {0x01, 0x01, 0xFF}, Outcome::Malformed},
        {&bits, {0x01, 0x03, 0xFF, 0x01, 0x00}, Outcome::Malformed},
    };
    for (const Case& c : cases) {
        codec::Response rsp;
        rsp.value = 0x5555;  // left from an earlier answer: must not survive
        const Outcome got = check_response(*c.request, frame_of(1, c.pdu), rsp);
        EXPECT_EQ(got, c.outcome) << int(c.pdu[0]) << " " << c.pdu.size();
        if (got == Outcome::Ok) {
            codec::Response full;
            ASSERT_EQ(codec::decode_response(codec::Bytes(c.pdu.data(), c.pdu.size()), full),
                      codec::CodecError::Ok);
            EXPECT_EQ(rsp.function, full.function);
            EXPECT_EQ(rsp.exception, codec::ExceptionCode::None);
            EXPECT_EQ(rsp.value, 0);
            EXPECT_EQ(rsp.payload.data(), c.pdu.data() + 2);
            EXPECT_EQ(rsp.payload.size(), full.payload.size());
        }
        if (got == Outcome::Exception) {
            EXPECT_EQ(rsp.exception, codec::ExceptionCode(0x02));
        }
    }
    codec::Response rsp;
    EXPECT_EQ(check_response(regs, frame_of(2, cases[0].pdu), rsp), Outcome::WrongUnitId);
}

// The engine's first look at an answer: a compare against the answer the request expects.
// Whatever it accepts, the full check calls Ok; it accepts exactly the expected answers.
TEST(ReadFastPaths, ExpectedAnswersAreWhatTheFullCheckCallsOk) {
    RequestInfo regs;
    regs.function = 0x03;
    regs.unit_id = 1;
    regs.quantity = 2;
    regs.answer_bytes = 4;
    RequestInfo bits = regs;
    bits.function = 0x01;
    bits.quantity = 9;
    bits.answer_bytes = 2;
    RequestInfo write = regs;  // no expected answer: never accepted here
    write.function = 0x06;
    write.answer_bytes = 0;
    struct Case {
        const RequestInfo* request;
        std::uint8_t unit;
        std::vector<std::uint8_t> pdu;
        bool expected;
    };
    const std::vector<Case> cases = {
        {&regs, 1, {0x03, 0x04, 0xAA, 0xBB, 0xCC, 0xDD}, true},
        {&regs, 2, {0x03, 0x04, 0xAA, 0xBB, 0xCC, 0xDD}, false},  // another unit
        {&regs, 1, {0x04, 0x04, 0xAA, 0xBB, 0xCC, 0xDD}, false},  // another function
        {&regs, 1, {0x03, 0x02, 0xAA, 0xBB}, false},
        {&regs, 1, {0x03, 0x04, 0xAA, 0xBB, 0xCC}, false},
        {&regs, 1, {0x03, 0x05, 0xAA, 0xBB, 0xCC, 0xDD}, false},  // byte count lies
        {&regs, 1, {0x83, 0x02, 0x00, 0x00, 0x00, 0x00}, false},
        {&regs, 1, {0x83, 0x02}, false},
        {&bits, 1, {0x01, 0x02, 0xFF, 0x01}, true},
        {&bits, 1, {0x01, 0x01, 0xFF}, false},
        {&write, 1, {0x06, 0x00, 0x01, 0x00, 0x02}, false},
    };
    for (const Case& c : cases) {
        const codec::TcpFrame frame = frame_of(c.unit, c.pdu);
        EXPECT_EQ(is_expected_read_answer(*c.request, frame), c.expected) << c.pdu.size();
        codec::Response rsp;
        if (c.expected) {
            EXPECT_EQ(check_response(*c.request, frame, rsp), Outcome::Ok);
        }
    }
}

}  // namespace
}  // namespace mbstorm::load
