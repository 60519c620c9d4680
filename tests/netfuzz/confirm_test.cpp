// The confirm stage on its own (netfuzz/confirm.hpp), against scripted replays: what a finding
// must show again, how often, and what the deadline and a lost target make of it.
#include "netfuzz/confirm.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "netfuzz/rules.hpp"

namespace {

using namespace mbstorm::netfuzz;

// Replays whose verdicts are given in turn (then none); `affordable` runs fit the deadline.
class ScriptedReplays : public Replayer {
  public:
    explicit ScriptedReplays(std::vector<Verdict> shown, unsigned affordable = 100)
        : shown_(std::move(shown)), affordable_(affordable) {}
    bool can_afford(unsigned runs) const override { return runs + this->runs <= affordable_; }
    Execution replay_alone(const Case&) override {
        Execution e;
        if (runs < shown_.size()) e.verdict = shown_[runs];
        ++runs;
        return e;
    }
    bool bring_back(const Execution&, const std::string& cause) override {
        charged.push_back(cause);
        return !target_stays_down;
    }
    unsigned runs = 0;
    std::vector<std::string> charged;
    bool target_stays_down = false;

  private:
    std::vector<Verdict> shown_;
    unsigned affordable_;
};

Verdict verdict(Oracle o, const std::string& rule) {
    Verdict v;
    v.oracle = o;
    v.rule = rule;
    return v;
}

Finding finding(const Verdict& v) {
    Finding f;
    f.verdict = v;
    f.confirmed = true;
    return f;
}

const Verdict kHang = verdict(Oracle::Hang, "no-response/fc03");
const Verdict kOther = verdict(Oracle::Hang, "no-response/fc06");
const Verdict kDeviation = verdict(Oracle::SpecDeviation, "wrong-byte-count/fc03");
const Verdict kRandomDrops = verdict(Oracle::Hang, kRandomDropRule);

TEST(Confirm, AFindingStandsOnlyIfItsCaseShowsItAgainAlone) {
    Finding f = finding(kDeviation);
    ScriptedReplays shows({kDeviation});
    EXPECT_EQ(ReplayCheck{}.replays_alone(f, shows), Confirmation::Confirmed);
    EXPECT_EQ(shows.runs, 1u);
    EXPECT_EQ(shows.charged, std::vector<std::string>{root_cause_key(kDeviation)});
    ScriptedReplays drifts({kOther});
    EXPECT_EQ(ReplayCheck{}.replays_alone(f, drifts), Confirmation::NotShown);
    EXPECT_EQ(drifts.charged, std::vector<std::string>{""}) << "another fault is charged nothing";
}

TEST(Confirm, ACrashConfirmedByItsSecondDeathIsNotReplayedAgain) {
    Finding f = finding(verdict(Oracle::Crash, "target-down/fc10"));
    ScriptedReplays none({});
    EXPECT_EQ(ReplayCheck{}.replays_alone(f, none), Confirmation::Confirmed);
    EXPECT_EQ(none.runs, 0u);
}

TEST(Confirm, ASilenceFromATargetThatDropsAtRandomMustShowFourTimes) {
    ReplayCheck check;
    Finding f = finding(kHang);
    EXPECT_TRUE(check.asks_random_drops_first(f));
    EXPECT_FALSE(check.asks_random_drops_first(finding(kRandomDrops))) << "that is the question";
    check.random_drops_answered(true);
    EXPECT_FALSE(check.asks_random_drops_first(f)) << "asked once";
    ScriptedReplays three({kHang, kHang, kHang, verdict(Oracle::None, "")});
    EXPECT_EQ(check.replays_alone(f, three), Confirmation::NotShown);
    EXPECT_EQ(three.runs, 4u);
    ScriptedReplays four({kHang, kHang, kHang, kHang});
    EXPECT_EQ(check.replays_alone(f, four), Confirmation::Confirmed);
    // Not a silence: once is enough, lossy target or not.
    Finding d = finding(kDeviation);
    ScriptedReplays once({kDeviation});
    EXPECT_EQ(check.replays_alone(d, once), Confirmation::Confirmed);
    EXPECT_EQ(once.runs, 1u);
}

TEST(Confirm, TheDeadlineKeepsAFindingUnconfirmedUnlessItIsLikelyARandomDrop) {
    Finding f = finding(kDeviation);
    ScriptedReplays no_time({kDeviation}, 0);
    EXPECT_EQ(ReplayCheck{}.replays_alone(f, no_time), Confirmation::KeptUnconfirmed);
    EXPECT_FALSE(f.confirmed);
    EXPECT_NE(f.note.find("not confirmed: --seconds ran out"), std::string::npos) << f.note;
    ReplayCheck lossy;
    lossy.random_drops_answered(true);
    Finding h = finding(kHang);
    ScriptedReplays two({kHang, kHang}, 2);
    EXPECT_EQ(lossy.replays_alone(h, two), Confirmation::CutShort);
    EXPECT_TRUE(h.confirmed);
}

TEST(Confirm, ATimingFaultMustShowOnEveryRun) {
    Case c;
    const std::string key = root_cause_key(kHang);
    ScriptedReplays twice({kHang, kHang});
    EXPECT_EQ(shows_every_time(c, key, twice), Confirmation::Confirmed);
    EXPECT_EQ(twice.runs, 2u);
    ScriptedReplays once({kHang, kOther});
    EXPECT_EQ(shows_every_time(c, key, once), Confirmation::NotShown);
    ScriptedReplays lost({kHang});
    lost.target_stays_down = true;
    EXPECT_EQ(shows_every_time(c, key, lost), Confirmation::TargetLost);
    ScriptedReplays cut({kHang}, 1);
    EXPECT_EQ(shows_every_time(c, key, cut), Confirmation::CutShort);
}

TEST(Confirm, TheRandomDropsQuestionAwaitsEachOfItsProbes) {
    TargetProfile p;
    p.probe_pdu = {0x03, 0x00, 0x00, 0x00, 0x01};
    const Case c = random_drops_case(p);
    ASSERT_EQ(c.steps.size(), 64u);
    EXPECT_EQ(c.cls, MutationClass::Repeated);
    for (std::size_t i = 0; i < c.steps.size(); ++i)
        EXPECT_EQ(c.steps[i].op, i % 2 ? Op::Await : Op::Send) << i;
    EXPECT_TRUE(drops_at_random(kRandomDrops));
    EXPECT_FALSE(drops_at_random(kHang));
}

}  // namespace
