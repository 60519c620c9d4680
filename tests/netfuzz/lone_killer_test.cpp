// Which request of a case of several kills the target alone (netfuzz/lone_killer.hpp), against
// a scripted campaign: the requests run alone in order, the first that leaves the target down
// is the one, and its restart is charged to its own root cause.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <set>
#include <string>
#include <vector>

#include "netfuzz/finding.hpp"
#include "netfuzz/lone_killer.hpp"
#include "netfuzz/rules.hpp"

namespace mbstorm::netfuzz {
namespace {

using Pdu = std::vector<std::uint8_t>;

// Runs each request case by its function code: `kills` leave the target down (a crash
// verdict naming that code), the rest are answered.
class ScriptedRuns final : public LoneRuns {
  public:
    std::set<std::uint8_t> kills;
    unsigned budget = 100;
    bool comes_back = true;
    std::vector<std::uint8_t> ran;
    std::vector<std::string> recovered;

    bool can_afford(unsigned runs) const override { return ran.size() + runs <= budget; }
    Execution run_request_alone(const Case& c) override {
        ran.push_back(c.function);
        Execution e;
        if (kills.count(c.function)) {
            e.target_down = true;
            e.verdict.oracle = Oracle::Crash;
            e.verdict.rule = target_down_rule(fmt::format("fc{:02X}", c.function));
            e.verdict.culprit_fc = c.function;
        }
        return e;
    }
    bool recover_from_death(const std::string& cause) override {
        recovered.push_back(cause);
        return comes_back;
    }
    bool settle_hang() override { return true; }
};

// A coalesced case: a read, a write, a read, in one send on one connection.
Case three_requests() {
    Pdu bytes;
    std::uint16_t tid = 1;
    for (const Pdu& pdu :
         {Pdu{0x03, 0, 0, 0, 1}, Pdu{0x06, 0, 5, 0x7E, 0x57}, Pdu{0x01, 0, 0, 0, 8}}) {
        const Pdu f = frame_pdu(pdu, tid++, 1);
        bytes.insert(bytes.end(), f.begin(), f.end());
    }
    Case c;
    c.cls = MutationClass::Coalesced;
    c.function = 0x03;
    c.steps.push_back(Step{Op::Send, 0, 0, 0, bytes});
    return c;
}

TEST(LoneKiller, TheRequestThatKillsAloneIsTheOneNotTheFirstLeftUnanswered) {
    ScriptedRuns runs;
    runs.kills = {0x06};
    const LoneKiller k = find_lone_killer(three_requests(), TargetProfile{}, runs);
    EXPECT_FALSE(k.lost);
    ASSERT_TRUE(k.request.has_value());
    EXPECT_EQ(k.request->function, 0x06);
    EXPECT_EQ(k.request->steps.size(), 1u);
    EXPECT_EQ(root_cause_key(k.run.verdict), "crash:target-down/fc06");
    EXPECT_EQ(runs.ran, (std::vector<std::uint8_t>{0x03, 0x06}));  // none after it
    EXPECT_EQ(runs.recovered, (std::vector<std::string>{"crash:target-down/fc06"}));
}

TEST(LoneKiller, NoneWhenTheRequestsKillOnlyTogetherOrTheBudgetEndsOrTheCaseIsOneRequest) {
    ScriptedRuns together;
    EXPECT_FALSE(find_lone_killer(three_requests(), TargetProfile{}, together).request);
    EXPECT_EQ(together.ran.size(), 3u);
    ScriptedRuns poor;
    poor.kills = {0x01};
    poor.budget = 2;
    EXPECT_FALSE(find_lone_killer(three_requests(), TargetProfile{}, poor).request);
    Case one = three_requests();
    one.steps.front().bytes = frame_pdu(Pdu{0x03, 0, 0, 0, 1}, 1, 1);
    ScriptedRuns single;
    single.kills = {0x03};
    EXPECT_FALSE(find_lone_killer(one, TargetProfile{}, single).request);
    EXPECT_TRUE(single.ran.empty());
}

TEST(LoneKiller, ATargetThatStaysDownEndsTheSearch) {
    ScriptedRuns runs;
    runs.kills = {0x03};
    runs.comes_back = false;
    const LoneKiller k = find_lone_killer(three_requests(), TargetProfile{}, runs);
    EXPECT_TRUE(k.lost);
    EXPECT_EQ(runs.ran.size(), 1u);
}

}  // namespace
}  // namespace mbstorm::netfuzz
