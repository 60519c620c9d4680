// The minimise stage of a campaign: a finding's case made as small and as right as it can be
// while its fault keeps showing. First delta debugging over frames, steps and PDU tails
// (minimize.hpp), then field level (field_repair.hpp): a range moved into the map where the 02
// seen may hide a check the target skips, a stub's invalid requests folded into its valid
// one's answer, and each wrong field of the culprit request made right while the very root
// cause still shows. Every candidate runs alone through a Rerun the campaign gives, which owns
// the target (restarts, hang settling, time and restart budgets): this unit holds only the
// decisions, so it is tested against scripted targets with no network.
#pragma once

#include <optional>
#include <string>

#include "codec/framing.hpp"
#include "netfuzz/case.hpp"
#include "netfuzz/device_model.hpp"
#include "netfuzz/executor.hpp"
#include "netfuzz/finding.hpp"

namespace mbstorm::netfuzz {

// One finding's candidates as they are tried: what they must show and why trying stopped.
struct Retrial {
    Retrial(Verdict v, std::string k, bool same, std::string charged)
        : first(std::move(v)), key(std::move(k)), same_key(same), charge(std::move(charged)) {}
    Verdict first;
    std::string key;              // its root cause
    bool same_key;                // the very root cause, not merely the same fault (see same_fault)
    std::string charge;           // the key restarts are charged to: the finding's first guise
    Execution last;               // the last candidate that showed it
    bool lost = false;            // the target did not come back
    bool cut = false;             // no run fits before the deadline
    bool restart_budget = false;  // a crash's restarts are spent
    bool stopped() const noexcept { return lost || cut || restart_budget; }
};

// How the stage runs a candidate against the target.
class Rerun {
  public:
    virtual ~Rerun() = default;
    // Whether `candidate`, run alone, shows r.first's fault again (its run kept in r.last);
    // false, with r's flags set, when no run could be made.
    virtual bool shows_again(const Case& candidate, Retrial& r) = 0;
    // `c` run alone once, the target brought back if it fell; nothing when no run fits the
    // time left or the target did not come back.
    virtual std::optional<Execution> run_once(const Case& c) = 0;
};

struct ShrinkContext {
    const DeviceModel& model;
    codec::Framing framing = codec::Framing::Mbap;
    unsigned budget = 64;       // delta debugging's runs (crashes and hangs: fewer)
    unsigned max_restarts = 3;  // a crash's, for the note when they run out
};

// Delta debugging; false when the deadline cut it short. Findings whose verdict rests on a
// silence's length or on repeats are left as found, with a note saying why.
bool minimise_finding(Finding& f, Rerun& rerun, const ShrinkContext& ctx);
// "02 where 03 is owed" from a request outside the map, re-run with its ranges inside:
// whatever deviation it then draws is the finding.
void move_ranges_into_map(Finding& f, Rerun& rerun, const ShrinkContext& ctx);
// An invalid request answered normally whose valid counterpart gets the very same, wrong,
// answer: the valid request's finding.
void merge_stub_answer(Finding& f, Rerun& rerun, const ShrinkContext& ctx);
// A write whose value is stored wrong shows on every connection: a mismatch read on another
// connection is that defect when the writer's own read-back shows it too (the case with every
// step on one connection, run twice: the read-back depends on what the registers held). It is
// the other connections' own (a per-connection cache) only when the writer reads it right.
void read_back_on_writers_connection(Finding& f, Rerun& rerun);
// Each wrong field of the culprit request made right in turn, kept right while the same root
// cause shows (restarts charged to `charge`); sets f.wrong_fields.
void narrow_wrong_fields(Finding& f, Rerun& rerun, const ShrinkContext& ctx,
                         const std::string& charge);

}  // namespace mbstorm::netfuzz
