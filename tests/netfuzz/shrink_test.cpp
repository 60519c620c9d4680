// The minimise stage on its own (netfuzz/shrink.hpp), against scripted targets: each candidate
// is judged by a function of the request it carries, as the campaign's Rerun would judge a run.
#include "netfuzz/shrink.hpp"

#include <gtest/gtest.h>

#include <functional>

#include "codec/limits.hpp"
#include "codec/mbap.hpp"
#include "codec/table.hpp"
#include "netfuzz/rules.hpp"
#include "netfuzz/wire.hpp"

namespace {

using namespace mbstorm::netfuzz;
using mbstorm::codec::Table;
using Pdu = std::vector<std::uint8_t>;
namespace lim = mbstorm::codec::limits;

// A target whose every answer is `judge` of the requests a case sends (the last one that fires).
class ScriptedTarget : public Rerun {
  public:
    using Judge = std::function<Verdict(const Pdu& pdu)>;
    explicit ScriptedTarget(Judge judge, unsigned runs_left = 1000)
        : judge_(std::move(judge)), runs_left_(runs_left) {}

    bool shows_again(const Case& candidate, Retrial& r) override {
        std::optional<Execution> e = run_once(candidate);
        if (!e) {
            r.cut = true;
            return false;
        }
        const bool same = r.same_key ? e->verdict && root_cause_key(e->verdict) == r.key
                                     : same_fault(r.first, e->verdict);
        if (!same) return false;
        r.last = std::move(*e);
        return true;
    }
    std::optional<Execution> run_once(const Case& c) override {
        if (runs_left_ == 0) return std::nullopt;
        --runs_left_;
        ++runs;
        Execution e;
        for (const Step& s : c.steps) {
            if (s.op != Op::Send || s.bytes.size() <= lim::kMbapHeader) continue;
            const Pdu pdu(s.bytes.begin() + lim::kMbapHeader, s.bytes.end());
            e.trace.push_back(TraceEvent{0, s.conn, TraceKind::Send, s.bytes, ""});
            if (Verdict v = judge_(pdu)) e.verdict = v;
            e.trace.push_back(TraceEvent{0, s.conn, TraceKind::Recv, answer(pdu), ""});
        }
        return e;
    }
    // What the target sends back: an echo of the request's first bytes, or a stub's constant.
    std::function<Pdu(const Pdu&)> answer = [](const Pdu& pdu) {
        return Pdu(pdu.begin(), pdu.begin() + std::min<std::size_t>(pdu.size(), 5));
    };
    unsigned runs = 0;

  private:
    Judge judge_;
    unsigned runs_left_;
};

Verdict deviation(const std::string& rule, int fc) {
    Verdict v;
    v.oracle = Oracle::SpecDeviation;
    v.rule = rule;
    v.culprit_fc = fc;
    return v;
}

Step send(const Pdu& pdu, std::uint16_t tid = 1) {
    return Step{Op::Send, 0, 0, 0, mbap_view(1, pdu, tid)};
}

Finding finding_of(const Case& c, const Verdict& v) {
    Finding f;
    f.verdict = v;
    f.fuzz_case = f.original_case = c;
    return f;
}

Pdu pdu_of(const Step& s) {
    return Pdu(s.bytes.begin() + lim::kMbapHeader, s.bytes.end());
}

DeviceModel holding_map() {
    DeviceModel m;
    m.table(Table::HoldingRegisters).ranges = {AddressRange{1000, 1039}};
    return m;
}

const std::string kOwes03 = "invalid-request-answered-normally(owes-03)/fc10";

// FC 10 whose handler never reads the byte count: only a byte count that disagrees with the
// quantity is the defect; wrong data or an address outside the map alone are answered as owed.
Verdict ignores_byte_count(const Pdu& pdu) {
    if (pdu.size() < 6 || pdu[0] != 0x10) return {};
    const unsigned quantity = mbstorm::codec::load_be16(pdu.data() + 3);
    if (pdu[5] != 2 * quantity) return deviation(kOwes03, 0x10);
    return {};
}

TEST(Shrink, EachFieldTheDefectDoesNotNeedIsMadeRight) {
    // Quantity 2 at 1000, byte count 6 (4 owed), two data bytes (6 announced), outside nothing.
    const Pdu wrong = {0x10, 0x03, 0xE8, 0, 2, 6, 0xAB, 0xCD};
    Case c;
    c.steps.push_back(send(wrong));
    Finding f = finding_of(c, deviation(kOwes03, 0x10));
    ScriptedTarget target(ignores_byte_count);
    const DeviceModel model = holding_map();
    narrow_wrong_fields(f, target, ShrinkContext{model}, f.key());
    EXPECT_EQ(f.wrong_fields, std::vector<std::string>{"byte-count"});
    // The data now agrees with the byte count still wrong: padded to six bytes.
    EXPECT_EQ(pdu_of(f.fuzz_case.steps[0]),
              (Pdu{0x10, 0x03, 0xE8, 0, 2, 6, 0xAB, 0xCD, 0, 0, 0, 0}));
    EXPECT_EQ(f.minimize_note, "field-level: wrong byte-count (data-length made right)");
    EXPECT_EQ(target.runs, 2u);  // one try per wrong field
    EXPECT_TRUE(f.minimized);
}

TEST(Shrink, AFieldWhoseRepairDrawsAnotherRootCauseStaysWrong) {
    // Address 0x2000 (outside the map) and a wrong byte count; the target answers that address
    // with 02 whatever else is wrong.
    auto judge = [](const Pdu& pdu) {
        if (mbstorm::codec::load_be16(pdu.data() + 1) >= 0x2000)
            return deviation("exception-02-where-03-owed", 0x10);
        return ignores_byte_count(pdu);
    };
    Case c;
    c.steps.push_back(send({0x10, 0x20, 0x00, 0, 1, 4, 0, 1, 0, 2}));
    Finding f = finding_of(c, deviation("exception-02-where-03-owed", 0x10));
    ScriptedTarget target(judge);
    const DeviceModel model = holding_map();
    narrow_wrong_fields(f, target, ShrinkContext{model}, f.key());
    // The byte count made right still shows the 02 (the address alone draws it): kept right.
    // The address made right draws another root cause: it stays wrong.
    EXPECT_EQ(f.wrong_fields, std::vector<std::string>{"address"});
    EXPECT_EQ(pdu_of(f.fuzz_case.steps[0]), (Pdu{0x10, 0x20, 0x00, 0, 1, 2, 0, 1}));
}

TEST(Shrink, NarrowingStopsWhenNoRunIsLeft) {
    Case c;
    c.steps.push_back(send({0x10, 0x03, 0xE8, 0, 2, 6, 0xAB, 0xCD}));
    Finding f = finding_of(c, deviation(kOwes03, 0x10));
    ScriptedTarget target(ignores_byte_count, 0);
    const DeviceModel model = holding_map();
    narrow_wrong_fields(f, target, ShrinkContext{model}, f.key());
    EXPECT_EQ(f.wrong_fields, (std::vector<std::string>{"byte-count", "data-length"}));
    EXPECT_EQ(f.minimize_note, "field-level: wrong byte-count, data-length, not narrowed further");
    EXPECT_FALSE(f.minimized);
}

TEST(Shrink, A02WhereA03IsOwedBecomesTheCheckSkippedOnceTheAddressIsInside) {
    // FC 10 past the end of the block (1039 + 2 registers): the target checks the address but
    // never the byte count, so inside the map the request is answered normally.
    auto judge = [](const Pdu& pdu) {
        const unsigned start = mbstorm::codec::load_be16(pdu.data() + 1);
        const unsigned quantity = mbstorm::codec::load_be16(pdu.data() + 3);
        if (start + quantity - 1 > 1039) return deviation("exception-02-where-03-owed", 0x10);
        return ignores_byte_count(pdu);
    };
    Case c;
    c.steps.push_back(send({0x10, 0x04, 0x0F, 0, 2, 3, 0, 1, 0}));
    Finding f = finding_of(c, deviation("exception-02-where-03-owed", 0x10));
    ScriptedTarget target(judge);
    const DeviceModel model = holding_map();
    move_ranges_into_map(f, target, ShrinkContext{model});
    EXPECT_EQ(f.key(), "spec-deviation:" + kOwes03);
    EXPECT_EQ(mbstorm::codec::load_be16(pdu_of(f.fuzz_case.steps[0]).data() + 1), 1000);
    EXPECT_NE(f.minimize_note.find("with its address inside the map"), std::string::npos);
}

TEST(Shrink, AStubsInvalidRequestIsTheValidRequestsFinding) {
    // FC 14 answered with the same bytes whatever it asks; a valid request's answer is wrong.
    auto judge = [](const Pdu& pdu) {
        if (pdu[0] != 0x14) return Verdict{};
        if (pdu.size() > 1 && pdu[1] == 0x07) {
            Verdict v;
            v.oracle = Oracle::MalformedResponse;
            v.rule = "undecodable-response(byte_count_mismatch)";
            v.culprit_fc = 0x14;
            return v;
        }
        return deviation("invalid-request-answered-normally(owes-03)/fc14", 0x14);
    };
    ScriptedTarget target(judge);
    target.answer = [](const Pdu&) { return Pdu{0x14, 0x00}; };
    Case c;
    c.steps.push_back(send({0x14, 0x01, 0x06}));
    Finding f = finding_of(c, judge({0x14, 0x01, 0x06}));
    f.trace = target.run_once(c)->trace;
    const DeviceModel model = holding_map();
    merge_stub_answer(f, target, ShrinkContext{model});
    EXPECT_EQ(f.oracle(), Oracle::MalformedResponse);
    // A stub whose answer follows the request keeps its own finding.
    ScriptedTarget echoing(judge);
    Finding g = finding_of(c, judge({0x14, 0x01, 0x06}));
    g.trace = echoing.run_once(c)->trace;
    merge_stub_answer(g, echoing, ShrinkContext{model});
    EXPECT_EQ(g.oracle(), Oracle::SpecDeviation);
}

TEST(Shrink, DeltaDebuggingKeepsTheOneStepThatFires) {
    Case c;
    c.cls = MutationClass::InvalidValues;
    c.steps.push_back(send({0x03, 0x03, 0xE8, 0, 1}, 1));
    c.steps.push_back(send({0x10, 0x03, 0xE8, 0, 1, 4, 0, 1, 0, 2}, 2));
    c.steps.push_back(send({0x03, 0x03, 0xE9, 0, 1}, 3));
    Finding f = finding_of(c, deviation(kOwes03, 0x10));
    ScriptedTarget target(ignores_byte_count);
    const DeviceModel model = holding_map();
    EXPECT_TRUE(minimise_finding(f, target, ShrinkContext{model}));
    ASSERT_EQ(f.fuzz_case.steps.size(), 1u);
    EXPECT_EQ(pdu_of(f.fuzz_case.steps[0])[0], 0x10);
    // With no run left it says the deadline cut it short.
    Finding g = finding_of(c, deviation(kOwes03, 0x10));
    ScriptedTarget no_time(ignores_byte_count, 0);
    EXPECT_FALSE(minimise_finding(g, no_time, ShrinkContext{model}));
    EXPECT_EQ(g.minimize_note, "minimisation cut short by --seconds");
}

}  // namespace

namespace {

// A target whose read-backs go wrong on the writer's connection too (`stores_wrong`), or only on
// the others' (a per-connection cache).
class ReadBackTarget : public Rerun {
  public:
    explicit ReadBackTarget(bool stores_wrong) : stores_wrong_(stores_wrong) {}
    bool shows_again(const Case&, Retrial&) override { return false; }
    std::optional<Execution> run_once(const Case& c) override {
        ++runs;
        bool one_connection = true;
        for (const Step& s : c.steps) one_connection = one_connection && s.conn == 0;
        Execution e;
        if (!one_connection || stores_wrong_)
            e.verdict =
                deviation(read_after_write_rule(!one_connection, "holding-registers", 0x16), 0x16);
        return e;
    }
    unsigned runs = 0;

  private:
    bool stores_wrong_;
};

Case written_then_read_elsewhere() {
    Case c;
    c.cls = MutationClass::StatefulCross;
    c.steps.push_back(send({0x16, 0x00, 0x10, 0xFF, 0x00, 0x00, 0xFF}));
    c.steps.push_back(Step{Op::Await, 0, 0, 0, {}});
    Step read = send({0x03, 0x00, 0x10, 0x00, 0x01}, 2);
    read.conn = 1;
    c.steps.push_back(read);
    return c;
}

// pymodbus-like: FC 16 stores a wrong value, which every connection reads back: one defect,
// named as the writer's own read-back shows it (not a second finding "on another connection").
TEST(Shrink, AMismatchOnAnotherConnectionIsTheWritersOwnWhenItReadsItWrongToo) {
    const Case c = written_then_read_elsewhere();
    Finding f =
        finding_of(c, deviation(read_after_write_rule(true, "holding-registers", 0x16), 0x16));
    ReadBackTarget target(true);
    read_back_on_writers_connection(f, target);
    EXPECT_EQ(f.verdict.rule, read_after_write_rule(false, "holding-registers", 0x16));
    for (const Step& s : f.fuzz_case.steps) EXPECT_EQ(s.conn, 0);
    EXPECT_EQ(target.runs, 2u) << "run once to leave its state, judged on the second";
}

// A per-connection cache: the writer reads its own value right; the other connection's
// mismatch is a defect of its own and stays so.
TEST(Shrink, AMismatchOnlyOtherConnectionsSeeStaysTheirs) {
    const Case c = written_then_read_elsewhere();
    const Verdict cross = deviation(read_after_write_rule(true, "holding-registers", 0x16), 0x16);
    Finding f = finding_of(c, cross);
    ReadBackTarget target(false);
    read_back_on_writers_connection(f, target);
    EXPECT_EQ(f.verdict.rule, cross.rule);
    EXPECT_EQ(f.fuzz_case.steps.back().conn, 1);
}

}  // namespace
