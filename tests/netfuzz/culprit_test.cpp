// What a case's culprits are named, before it is sent: the campaign skips a case carrying a
// culprit known to crash or hang the target, and charges a batch death to it.
#include <gtest/gtest.h>

#include <algorithm>

#include "netfuzz/culprit.hpp"

namespace {

using namespace mbstorm::netfuzz;

Case one_frame(MutationClass cls, std::vector<std::uint8_t> adu) {
    Case c;
    c.cls = cls;
    c.function = adu[7];
    c.steps.push_back(Step{Op::Send, 0, 0, 0, std::move(adu)});
    return c;
}

bool has(const std::vector<std::string>& v, const std::string& s) {
    return std::find(v.begin(), v.end(), s) != v.end();
}

// FC 0F with quantity 0 (invalid: 03 owed), protocol id 1. A target that never looks at the
// protocol id hands it to its FC 0F handler: a crash known there ("fc0F/invalid") must be
// recognised in this case too, or every such case kills the target again (the first
// multi-fault target died in nearly every batch once all its crashes were known).
TEST(Culprit, AFrameWithANonZeroProtocolIdIsAlsoNamedByTheHandlerItReaches) {
    TargetProfile profile;
    const std::vector<std::uint8_t> adu = {0x00, 0x01, 0x00, 0x01, 0x00, 0x07, 0x01,
                                           0x0F, 0x00, 0x10, 0x00, 0x00, 0x00};
    const auto sig = signatures(one_frame(MutationClass::ProtocolId, adu), profile);
    EXPECT_TRUE(has(sig, "protocol-id"));
    EXPECT_TRUE(has(sig, "fc0F/invalid"));
    // The same frame with protocol id 0 is its handler's only.
    std::vector<std::uint8_t> plain = adu;
    plain[3] = 0x00;
    EXPECT_EQ(signatures(one_frame(MutationClass::InvalidValues, plain), profile),
              std::vector<std::string>{"fc0F/invalid"});
}

// A valid and an invalid request of one handler are different culprits; every frame of a
// coalesced send is named.
TEST(Culprit, EachFrameIsNamedByItsHandlerAndWhetherItIsValid) {
    TargetProfile profile;
    std::vector<std::uint8_t> two = {0x00, 0x01, 0x00, 0x00, 0x00, 0x06, 0x01, 0x03,
                                     0x00, 0x00, 0x00, 0x01, 0x00, 0x02, 0x00, 0x00,
                                     0x00, 0x06, 0x01, 0x03, 0x00, 0x00, 0x00, 0x00};
    const auto sig = signatures(one_frame(MutationClass::Coalesced, two), profile);
    EXPECT_EQ(sig, (std::vector<std::string>{"fc03/valid", "fc03/invalid"}));
    EXPECT_EQ(culprit_of("target-down/fc0F"), "fc0F");
    EXPECT_EQ(culprit_of("answers-nonzero-protocol-id"), "");
}

// Once FC 0F's invalid requests are known to crash the target, cases carrying one are not sent
// again; its valid requests, and a stateful case's read-backs, still are. Crashed by more than
// one kind of request, the whole handler is skipped.
TEST(CostlyCases, ACaseCarryingAKnownCrashIsNotSentAgain) {
    TargetProfile profile;
    CostlyCases costly(profile);
    const Case invalid = one_frame(MutationClass::InvalidValues,
                                   {0, 1, 0, 0, 0, 6, 1, 0x0F, 0x00, 0x10, 0x00, 0x00});
    const Case valid = one_frame(MutationClass::ValidLimits,
                                 {0, 1, 0, 0, 0, 8, 1, 0x0F, 0x00, 0x10, 0x00, 0x01, 0x01, 0x01});
    EXPECT_FALSE(costly.would_retrigger(invalid));
    costly.learn("fc0F", invalid);
    EXPECT_TRUE(costly.would_retrigger(invalid));
    EXPECT_FALSE(costly.would_retrigger(valid));
    // A stateful case about another write, reading back over FC 0F's handler: still sent.
    Case stateful = valid;
    stateful.cls = MutationClass::StatefulSame;
    stateful.function = 0x05;
    stateful.steps.insert(stateful.steps.begin(), invalid.steps.front());
    EXPECT_FALSE(costly.would_retrigger(stateful));
    costly.learn_handler("fc0F");
    EXPECT_TRUE(costly.would_retrigger(valid));
}

TEST(CostlyCases, OnceTheStreamIsLostOnAWrongLengthOnlyOneSuchRequestInSixteenGoes) {
    TargetProfile profile;
    CostlyCases costly(profile);
    // FC 06 with a PDU one byte short.
    const Case short_write =
        one_frame(MutationClass::Truncated, {0, 1, 0, 0, 0, 5, 1, 0x06, 0x00, 0x10, 0x00});
    EXPECT_FALSE(costly.would_retrigger(short_write));
    costly.length_mismatch_loses_the_stream();
    unsigned sent = 0;
    for (int i = 0; i < 64; ++i) sent += !costly.would_retrigger(short_write);
    EXPECT_EQ(sent, 4u);
}

}  // namespace
