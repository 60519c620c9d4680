// The attribute stage over batch results made here: known root causes are hits, not suspects;
// a lane break a known root cause explains is not re-run; the candidates for a whole-target
// death come lane by lane from where each broke.
#include "netfuzz/attribute.hpp"

#include <gtest/gtest.h>

#include <set>
#include <string>
#include <vector>

#include "netfuzz/oracle.hpp"
#include "netfuzz/rules.hpp"

namespace mbstorm::netfuzz {
namespace {

using Indexes = std::vector<std::size_t>;

LaneBreak closed_after(std::size_t previous, std::size_t unanswered, bool exception) {
    LaneBreak b;
    b.closed = true;
    b.has_previous = true;
    b.previous_case = previous;
    b.previous_exception = exception;
    b.previous_culprit = "fc03-valid";
    b.unanswered_case = unanswered;
    b.unanswered_culprit = "fc06";
    b.unanswered = {unanswered};
    return b;
}

TEST(Attribute, TheKeysOfALaneBreakGoFromTheMostSpecific) {
    LaneBreak b = closed_after(3, 4, true);
    b.length_mismatch = true;
    b.unanswered_invalid = true;
    const std::vector<std::string> keys = lane_break_keys(b, LengthMismatchClose::LosesTheStream);
    ASSERT_EQ(keys.size(), 5u);
    EXPECT_EQ(keys[0], std::string("stream:") + kStreamLostRule);
    EXPECT_EQ(keys[1], std::string("unexpected-close:") + kClosesOnInvalidRequestRule);
    EXPECT_EQ(keys[2], std::string("unexpected-close:") + after_exception_rule(true));
    EXPECT_EQ(keys[3], std::string("unexpected-close:") + after_request_rule(true, "fc03-valid"));
    EXPECT_EQ(keys[4], std::string("unexpected-close:") + unanswered_rule(true, "fc06"));
    // A target that refuses such a frame closes on it: the invalid-request policy.
    EXPECT_EQ(lane_break_keys(b, LengthMismatchClose::RefusesTheFrame)[0],
              std::string("unexpected-close:") + kClosesOnInvalidRequestRule);
}

TEST(Attribute, KnownVerdictsAndExplainedBreaksAreHitsTheRestSuspects) {
    BatchResult br;
    br.suspects = {9, 2, 11, 12, 21};
    Verdict known_one{Oracle::SpecDeviation, "known", -1, "", "", ""};
    Verdict new_one{Oracle::SpecDeviation, "new", -1, "", "", ""};
    br.verdicts = {{5, known_one}, {7, new_one}, {2, new_one}};
    br.breaks = {closed_after(11, 12, true), closed_after(20, 21, false)};
    const std::string explained =
        std::string("unexpected-close:") + after_exception_rule(true);  // the first break's
    std::multiset<std::size_t> hits;
    const Indexes suspects = triage(
        br, LengthMismatchClose::NotAsked,
        [&](const Verdict& v, std::size_t ci) {
            if (v.rule != "known") return false;
            hits.insert(ci);
            return true;
        },
        [&](const std::string& key, std::size_t ci) {
            if (key != explained) return false;
            hits.insert(ci);
            return true;
        });
    // 2 once (a suspect and a new verdict), 7 new, 9 its own, 21 of the unexplained break; 11
    // and 12 explained by a known root cause.
    EXPECT_EQ(suspects, (Indexes{2, 7, 9, 21}));
    EXPECT_EQ(hits, (std::multiset<std::size_t>{5, 11}));
}

TEST(Attribute, AWholeTargetDeathIsLookedForLaneByLaneFromWhereEachBroke) {
    BatchResult br;
    LaneBreak a, b;
    a.unanswered = {4, 8, 12};
    b.unanswered = {5, 9};
    br.breaks = {a, b};
    EXPECT_EQ(batch_culprit_candidates(br, {1, 9, 3}, 16), (Indexes{4, 5, 8, 9, 12, 1, 3}));
}

}  // namespace
}  // namespace mbstorm::netfuzz
