// The rule texts (netfuzz/rules.hpp) are findings' identities: saved finding.json files and
// replays compare them byte for byte. Each function that puts one together must give exactly
// the text the fuzzer wrote before the rules were named in one place.
#include <gtest/gtest.h>

#include "netfuzz/finding.hpp"
#include "netfuzz/rules.hpp"

namespace {

using namespace mbstorm::netfuzz;

TEST(Rules, ExceptionRulesKeepTheirTexts) {
    EXPECT_EQ(exception_where_owed_rule(0x02, 0x03), "exception-02-where-03-owed");
    EXPECT_EQ(exception_where_owed_rule(0x04, 0x01), "exception-04-where-01-owed");
    EXPECT_EQ(exception_where_owed_prefix(0x02), "exception-02-where-");
    EXPECT_EQ(exception_where_owed_rule(0x02, 0x03).rfind(exception_where_owed_prefix(0x02), 0),
              0u);
    EXPECT_EQ(exception_to_valid_request_rule(0x03), "exception-03-to-valid-request");
    EXPECT_EQ(invalid_answered_normally_rule(0x03, 0x0F),
              "invalid-request-answered-normally(owes-03)/fc0F");
    EXPECT_EQ(std::string(kSubFunctionNot01Rule), "unknown-sub-function-not-refused-with-01");
}

TEST(Rules, SilenceRulesKeepTheirTexts) {
    EXPECT_EQ(unanswered_rule(false, "fc07"), "no-answer/fc07");
    EXPECT_EQ(unanswered_rule(true, "fc10"), "close-with-request-pending/fc10");
    EXPECT_EQ(unanswered_rule(true, kPartialFrameCulprit),
              "close-with-request-pending/partial-frame");
    EXPECT_EQ(after_request_rule(false, "fc03"), "drops-requests-after/fc03");
    EXPECT_EQ(after_request_rule(true, "unknown-fc"), "closes-after/unknown-fc");
    EXPECT_EQ(std::string(after_exception_rule(false)), "drops-requests-after-exception");
    EXPECT_EQ(std::string(after_exception_rule(true)), "closes-after-exception");
    EXPECT_EQ(std::string(kClosesOnInvalidRequestRule),
              "close-with-request-pending/invalid-request");
    EXPECT_EQ(std::string(kStreamLostRule), "stream-lost-after-pdu-length-mismatch");
}

TEST(Rules, WholeTargetRulesKeepTheirTexts) {
    EXPECT_EQ(target_down_rule("fc0F"), "target-down/fc0F");
    EXPECT_EQ(target_down_rule(kCapacityCulprit), "target-down/capacity");
    EXPECT_EQ(rule_with_culprit(kWholeServerHangRule, "fc14"), "whole-server-hang/fc14");
    EXPECT_EQ(rule_with_culprit(kTargetDownRule, kPipelinedBatchCulprit),
              "target-down/pipelined-batch");
    EXPECT_EQ(stalls_other_connections_rule(kPartialFrameCulprit),
              "stalls-other-connections(partial-frame)");
    EXPECT_EQ(stalls_other_connections_rule(kExceptionHeld), "stalls-other-connections(exception)");
    EXPECT_EQ(std::string(kCapacityUnservedRule), "capacity/accepted-connections-unserved");
}

TEST(Rules, ResponseRulesKeepTheirTexts) {
    EXPECT_EQ(function_culprit(0x0F), "fc0F");
    EXPECT_EQ(function_culprit(0x2B), "fc2B");
    EXPECT_EQ(answers_discarded_rule("bad-crc"), "answers-bad-crc");
    EXPECT_EQ(unmapped_address_rule("holding_registers"),
              "unmapped-address-answered-normally(holding_registers)");
    EXPECT_EQ(undecodable_response_rule("byte_count_mismatch"),
              "undecodable-response(byte_count_mismatch)");
    EXPECT_EQ(read_after_write_rule(false, "holding-registers", 0x16),
              "read-after-write-mismatch(holding-registers)/fc16");
    EXPECT_EQ(read_after_write_rule(true, "coils", 0x0F),
              "read-after-write-mismatch-other-connection(coils)/fc0F");
}

// The parts stay where rule_stem and culprit_of (campaign, finding keys) cut them.
TEST(Rules, BuiltRulesCutIntoTheirStemAndCulprit) {
    EXPECT_EQ(rule_stem(invalid_answered_normally_rule(0x03, 0x10)), kInvalidAnsweredNormallyRule);
    EXPECT_EQ(rule_stem(stalls_other_connections_rule(kRequestHeld)), kStallsOtherConnectionsRule);
    EXPECT_EQ(rule_stem(target_down_rule("fc05")), kTargetDownRule);
    EXPECT_EQ(rule_stem(unanswered_rule(false, "fc05")), kNoAnswerRule);
}

}  // namespace
