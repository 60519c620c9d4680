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

}  // namespace
