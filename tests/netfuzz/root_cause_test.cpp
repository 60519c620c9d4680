// Root-cause identity: the same fault under other function codes, unit ids and codec reasons
// is one key; different faults are different keys. And the --dict parser.
#include <gtest/gtest.h>

#include "codec/bytes.hpp"
#include "netfuzz/dictionary.hpp"
#include "netfuzz/finding.hpp"
#include "netfuzz/oracle.hpp"

namespace mbstorm::netfuzz {
namespace {

std::vector<std::uint8_t> adu(const std::vector<std::uint8_t>& pdu, std::uint8_t unit = 1,
                              std::uint16_t pid = 0) {
    std::vector<std::uint8_t> f(7 + pdu.size());
    codec::store_be16(f.data(), 0x0102);
    codec::store_be16(f.data() + 2, pid);
    codec::store_be16(f.data() + 4, static_cast<std::uint16_t>(pdu.size() + 1));
    f[6] = unit;
    std::copy(pdu.begin(), pdu.end(), f.begin() + 7);
    return f;
}

TargetProfile root_cause_profile() {
    TargetProfile p;
    p.probe_pdu = {0x03, 0, 0, 0, 1};
    return p;
}

// The verdict for answering `request` with `response` (both PDUs).
Verdict judge(const std::vector<std::uint8_t>& request, const std::vector<std::uint8_t>& response,
              std::uint8_t unit = 1, std::uint16_t pid = 0) {
    const auto rq_adu = adu(request, unit, pid);
    RequestInfo rq;
    describe_request(rq_adu, root_cause_profile(), rq);
    return judge_response(rq, adu(response, unit), root_cause_profile());
}

TEST(RootCause, AnsweringProtocolIdIsOneRootCauseWhateverTheFunctionOrUnit) {
    const Verdict a = judge({0x03, 0, 0, 0, 1}, {0x03, 2, 0, 0}, 1, 0x0001);
    const Verdict b = judge({0x04, 0, 9, 0, 1}, {0x04, 2, 0, 0}, 7, 0x8000);
    ASSERT_TRUE(a);
    EXPECT_EQ(root_cause_key(a), "spec-deviation:answers-nonzero-protocol-id");
    EXPECT_EQ(root_cause_key(a), root_cause_key(b));
    EXPECT_EQ(a.culprit_fc, 0x03);
    EXPECT_EQ(b.culprit_fc, 0x04);
    EXPECT_EQ(b.culprit_unit, 7);
}

TEST(RootCause, TheSameWrongExceptionUnderOtherCodecReasonsIsOneRootCause) {
    // 03 owed for a quantity out of range and for a byte count that disagrees: 02 seen.
    const Verdict q = judge({0x0F, 0, 0, 0, 0, 0}, {0x8F, 0x02});
    const Verdict bc = judge({0x0F, 0, 0, 0, 8, 2, 0xFF, 0}, {0x8F, 0x02});
    ASSERT_TRUE(q);
    ASSERT_TRUE(bc);
    EXPECT_EQ(root_cause_key(q), "spec-deviation:exception-02-where-03-owed");
    EXPECT_EQ(root_cause_key(q), root_cause_key(bc));
}

// One root cause per check a handler skips (v1.1b3's flow charts): FC 0F's quantity and byte
// count are one check (03), its address range another (02). pymodbus, which ignores FC 0F's
// quantity, once had a finding for each field of the one check.
TEST(RootCause, TwoChecksUnderOneFunctionAreTwoRootCausesOneCheckIsOne) {
    // A byte count that disagrees, a quantity of 0, both answered normally: the 03 check.
    const Verdict bc = judge({0x0F, 0, 0, 0, 8, 2, 0xFF, 0}, {0x0F, 0, 0, 0, 8});
    const Verdict q = judge({0x0F, 0, 0, 0, 0, 0}, {0x0F, 0, 0, 0, 0});
    // Eight coils from 0xFFFC run past 0xFFFF: the 02 check.
    const Verdict range = judge({0x0F, 0xFF, 0xFC, 0, 8, 1, 0xFF}, {0x0F, 0xFF, 0xFC, 0, 8});
    ASSERT_TRUE(bc);
    ASSERT_TRUE(q);
    ASSERT_TRUE(range);
    EXPECT_EQ(root_cause_key(bc), root_cause_key(q));
    EXPECT_NE(root_cause_key(bc), root_cause_key(range));
    // Another function's handler is another root cause.
    const Verdict fc10 = judge({0x10, 0, 0, 0, 0, 0}, {0x10, 0, 0, 0, 0});
    ASSERT_TRUE(fc10);
    EXPECT_NE(root_cause_key(bc), root_cause_key(fc10));
    EXPECT_EQ(rule_stem(bc.rule), rule_stem(range.rule));  // minimisation may move between them
}

TEST(RootCause, CulpritsNameTheHandlerNotTheRequest) {
    RequestInfo valid, invalid, unknown;
    const auto a = adu({0x03, 0, 0, 0, 1}), b = adu({0x03, 0, 0, 0, 200}), c = adu({0x41});
    describe_request(a, root_cause_profile(), valid);
    describe_request(b, root_cause_profile(), invalid);
    describe_request(c, root_cause_profile(), unknown);
    EXPECT_EQ(culprit_text(MutationClass::ValidLimits, &valid), "fc03");
    EXPECT_EQ(culprit_text(MutationClass::InvalidValues, &invalid), "fc03");
    EXPECT_EQ(culprit_text(MutationClass::UnknownFunction, &unknown), "unknown-fc");
    // A transport mutation is blamed on how the bytes arrived.
    EXPECT_EQ(culprit_text(MutationClass::Split, &valid), "partial-frame");
    EXPECT_EQ(culprit_text(MutationClass::Drip, &valid), "partial-frame");
    EXPECT_EQ(culprit_text(MutationClass::Flood, nullptr), "flood");
    EXPECT_EQ(culprit_text(MutationClass::Coalesced, nullptr), "coalesced");
}

// A stream lost after a request of the wrong length shows as a close, silence or a stray
// answer depending on timing (libmodbus frames by function code): one root cause.
TEST(RootCause, StreamLostAfterAPduLengthMismatchIsOneRootCauseUnderAnyOracle) {
    const Verdict closed{Oracle::UnexpectedClose, kStreamLostRule, 0x10, "", "", ""};
    const Verdict silent{Oracle::Hang, kStreamLostRule, 0x01, "", "", ""};
    const Verdict stray{Oracle::MalformedResponse, kStreamLostRule, -1, "", "", ""};
    EXPECT_EQ(root_cause_key(closed), root_cause_key(silent));
    EXPECT_EQ(root_cause_key(closed), root_cause_key(stray));
    EXPECT_TRUE(same_fault(closed, stray));
    const Verdict other{Oracle::Hang, "drops-requests-after-exception", 0x01, "", "", ""};
    EXPECT_NE(root_cause_key(silent), root_cause_key(other));
    EXPECT_FALSE(same_fault(silent, other));
}

TEST(RootCause, SameFaultComparesOracleAndRuleStem) {
    Verdict a{Oracle::Crash, "target-down/fc0F", 0x0F, "", "", ""};
    Verdict b{Oracle::Crash, "target-down/pipelined-batch", -1, "", "", ""};
    Verdict c{Oracle::Hang, "whole-server-hang/fc0F", 0x0F, "", "", ""};
    EXPECT_TRUE(same_fault(a, b));
    EXPECT_FALSE(same_fault(a, c));
    EXPECT_NE(root_cause_key(a), root_cause_key(b));
}

TEST(Dictionary, AflEntriesWordsAndTokens) {
    const Result<Dictionary> parsed = parse_dictionary(
        "# comment\n"
        "setpoint=\"\\x10\\x00\"\n"
        "  0x2001\n"
        "40\n"
        "\"\\x03\\x00\\x00\\x00\\x0A\"\n"
        "quote=\"a\\\"\"\n"
        "\n",
        "my.dict");
    ASSERT_TRUE(parsed.ok()) << parsed.error().text();
    const Dictionary& d = *parsed;
    EXPECT_EQ(d.words, (std::vector<std::uint16_t>{0x1000, 0x2001, 40, 0x6122}));
    ASSERT_EQ(d.tokens.size(), 1u);
    EXPECT_EQ(d.tokens[0], (std::vector<std::uint8_t>{3, 0, 0, 0, 10}));
}

TEST(Dictionary, BadLinesNameFileAndLine) {
    Error error = parse_dictionary("0x10\nname=\"\\q\"\n", "x.dict").error();
    EXPECT_EQ(error.code(), ErrorCode::InvalidInput);
    EXPECT_EQ(error.place(), "x.dict:2") << error.text();
    EXPECT_EQ(error.text().rfind("x.dict:2: ", 0), 0u) << error.text();
    error = parse_dictionary("70000\n", "x.dict").error();
    EXPECT_EQ(error.place(), "x.dict:1") << error.text();
    error = parse_dictionary("\"\"\n", "x.dict").error();
    EXPECT_NE(error.message().find("empty"), std::string::npos) << error.text();
}

}  // namespace
}  // namespace mbstorm::netfuzz
