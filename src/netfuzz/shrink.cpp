#include "netfuzz/shrink.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <utility>
#include <vector>

#include "codec/exception_code.hpp"
#include "codec/limits.hpp"
#include "codec/mbap.hpp"
#include "netfuzz/field_repair.hpp"
#include "netfuzz/minimize.hpp"
#include "netfuzz/rules.hpp"
#include "netfuzz/wire.hpp"

namespace mbstorm::netfuzz {
namespace {

namespace lim = codec::limits;

// How big a reproducer is: its steps first, then its bytes.
std::pair<std::size_t, std::size_t> size_of(const Case& c) {
    std::size_t bytes = 0;
    for (const Step& s : c.steps) bytes += s.bytes.size();
    return {c.steps.size(), bytes};
}

void add_note(Finding& f, const std::string& note) {
    f.minimize_note += (f.minimize_note.empty() ? "" : "; ") + note;
}

// The candidate's run becomes the finding's: its case, verdict and trace.
void take(Finding& f, Case c, Execution e) {
    f.fuzz_case = std::move(c);
    f.verdict = std::move(e.verdict);
    f.trace = std::move(e.trace);
    f.minimized = true;
}

// One request frame (any framing) with its ranges made to fit the map with their counts (a
// start inside the table whose count runs past its block's end is outside the map too); false
// when the step is not one such frame of function `fc`, or nothing moved.
bool move_into_map(Step& s, int fc, const ShrinkContext& ctx) {
    std::optional<std::vector<std::uint8_t>> mbap = step_request(s, fc, ctx.framing);
    if (!mbap) return false;
    std::optional<std::vector<std::uint8_t>> pdu;
    for (const RequestField range : {RequestField::Address, RequestField::WriteAddress}) {
        const codec::Bytes now =
            pdu ? codec::Bytes(*pdu) : codec::Bytes(*mbap).subspan(lim::kMbapHeader);
        if (auto moved = with_field_repaired(now, range, ctx.model)) pdu = std::move(moved);
    }
    if (!pdu) return false;
    std::copy(pdu->begin(), pdu->end(), mbap->begin() + lim::kMbapHeader);
    set_step_request(s, *mbap, ctx.framing);
    return true;
}

// The one send step holding a whole request frame of function `fc`; nothing when there is no
// such step or more than one.
std::optional<std::size_t> only_request_step(const Case& c, int fc, codec::Framing framing) {
    std::optional<std::size_t> at;
    for (std::size_t i = 0; i < c.steps.size(); ++i) {
        if (!step_request(c.steps[i], fc, framing)) continue;
        if (at) return std::nullopt;
        at = i;
    }
    return at;
}

std::vector<std::uint8_t> request_pdu(const Step& s, int fc, codec::Framing framing) {
    const auto mbap = step_request(s, fc, framing);
    return std::vector<std::uint8_t>(mbap->begin() + lim::kMbapHeader, mbap->end());
}

// The step's request with `pdu` in place of its own (the MBAP length follows).
void set_request_pdu(Step& s, int fc, const std::vector<std::uint8_t>& pdu,
                     codec::Framing framing) {
    auto mbap = *step_request(s, fc, framing);
    mbap.resize(lim::kMbapHeader);
    mbap.insert(mbap.end(), pdu.begin(), pdu.end());
    codec::store_be16(mbap.data() + 4, static_cast<std::uint16_t>(pdu.size() + 1));
    set_step_request(s, mbap, framing);
}

}  // namespace

bool minimise_finding(Finding& f, Rerun& rerun, const ShrinkContext& ctx) {
    const Case& c = f.original_case;
    if (depends_on_line_timing(c.cls)) {
        // Confirmed, but each try would again be at the scheduler's mercy.
        f.minimize_note = "not minimised: its verdict rests on a silence's length";
        return true;
    }
    if (c.cls == MutationClass::Repeated) {
        // Fewer repeats only make the drop less likely to show.
        f.minimize_note = "not minimised: each repeat is a chance for the drop to show";
        return true;
    }
    Retrial r{f.verdict, f.key(), false, f.key()};
    auto reproduces = [&](const Case& candidate) { return rerun.shows_again(candidate, r); };
    // Crashes and hangs cost a restart or a timeout per try: a smaller budget, whole frames
    // only.
    const bool costly = f.oracle() == Oracle::Crash || f.oracle() == Oracle::Hang;
    Case small = minimize_case(c, reproduces, costly ? std::min(8u, ctx.budget / 3) : ctx.budget,
                               !costly, ctx.framing);
    if (size_of(small) < size_of(c) && r.last.verdict) take(f, std::move(small), std::move(r.last));
    if (r.cut) {
        f.minimize_note = "minimisation cut short by --seconds";
        return false;
    }
    if (r.restart_budget)
        f.minimize_note = fmt::format("minimisation stopped: a crash may cost at most {} restarts",
                                      ctx.max_restarts);
    return true;
}

void move_ranges_into_map(Finding& f, Rerun& rerun, const ShrinkContext& ctx) {
    const std::string address_refused_where_other_owed = exception_where_owed_prefix(
        static_cast<std::uint8_t>(codec::ExceptionCode::IllegalDataAddress));
    if (f.verdict.oracle != Oracle::SpecDeviation ||
        f.verdict.rule.rfind(address_refused_where_other_owed, 0) != 0 || ctx.model.empty())
        return;
    Case repaired = f.fuzz_case;
    bool changed = false;
    for (Step& s : repaired.steps) changed = move_into_map(s, f.verdict.culprit_fc, ctx) || changed;
    if (!changed) return;
    std::optional<Execution> e = rerun.run_once(repaired);
    if (!e || e->verdict.oracle != Oracle::SpecDeviation) return;
    add_note(f, fmt::format("field-level: with its address inside the map, {} became {}",
                            f.verdict.rule, e->verdict.rule));
    take(f, std::move(repaired), std::move(*e));
}

void merge_stub_answer(Finding& f, Rerun& rerun, const ShrinkContext& ctx) {
    if (f.verdict.oracle != Oracle::SpecDeviation || f.verdict.culprit_fc < 0 ||
        f.verdict.rule.rfind(kInvalidAnsweredNormallyRule, 0) != 0)
        return;
    const auto fc = static_cast<std::uint8_t>(f.verdict.culprit_fc);
    const auto valid = valid_request_in_map(fc, ctx.model);
    Case plain = f.fuzz_case;
    std::vector<Step*> sends;
    for (Step& s : plain.steps)
        if (s.op == Op::Send) sends.push_back(&s);
    const auto mbap = sends.size() == 1 ? step_request(*sends[0], fc, ctx.framing) : std::nullopt;
    if (!valid || !mbap) return;
    set_step_request(
        *sends[0], mbap_view((*mbap)[lim::kMbapHeader - 1], *valid, codec::load_be16(mbap->data())),
        ctx.framing);
    std::optional<Execution> e = rerun.run_once(plain);
    if (!e) return;
    const bool wrong = e->verdict.oracle == Oracle::SpecDeviation ||
                       e->verdict.oracle == Oracle::MalformedResponse;
    const std::vector<std::uint8_t> answer = answered_bytes(f.trace);
    if (!wrong || answer.empty() || answered_bytes(e->trace) != answer) return;
    add_note(f, fmt::format("field-level: a valid request got the same answer, so the handler "
                            "does not read the request; {} became {}",
                            f.verdict.rule, e->verdict.rule));
    take(f, std::move(plain), std::move(*e));
}

void read_back_on_writers_connection(Finding& f, Rerun& rerun) {
    const std::string same = same_connection_rule(f.verdict.rule);
    if (f.verdict.oracle != Oracle::SpecDeviation || same.empty()) return;
    Case one = f.fuzz_case;
    for (Step& s : one.steps) s.conn = 0;
    one.cls = MutationClass::StatefulSame;
    if (!rerun.run_once(one)) return;  // leaves the registers as the judged run finds them
    std::optional<Execution> e = rerun.run_once(one);
    if (!e || e->verdict.rule != same) return;
    add_note(f, fmt::format("the writer's own read-back shows it too: {} became {}", f.verdict.rule,
                            same));
    take(f, std::move(one), std::move(*e));
}

void narrow_wrong_fields(Finding& f, Rerun& rerun, const ShrinkContext& ctx,
                         const std::string& charge) {
    const int fc = f.verdict.culprit_fc;
    const auto at = only_request_step(f.fuzz_case, fc, ctx.framing);
    if (!at) return;
    const std::vector<RequestField> wrong =
        wrong_fields(request_pdu(f.fuzz_case.steps[*at], fc, ctx.framing), ctx.model);
    Retrial r{f.verdict, f.key(), true, charge};
    std::vector<std::string> made_right;
    for (const RequestField field : wrong) {
        const auto repaired = with_field_repaired(
            request_pdu(f.fuzz_case.steps[*at], fc, ctx.framing), field, ctx.model);
        if (!repaired) continue;
        Case candidate = f.fuzz_case;
        set_request_pdu(candidate.steps[*at], fc, *repaired, ctx.framing);
        if (!rerun.shows_again(candidate, r)) {
            if (r.stopped()) break;
            continue;
        }
        take(f, std::move(candidate), std::move(r.last));
        made_right.emplace_back(field_name(field));
    }
    f.wrong_fields.clear();
    for (const RequestField field :
         wrong_fields(request_pdu(f.fuzz_case.steps[*at], fc, ctx.framing), ctx.model))
        f.wrong_fields.emplace_back(field_name(field));
    if (wrong.empty()) return;
    add_note(
        f,
        fmt::format(
            "field-level: wrong {}{}{}",
            f.wrong_fields.empty() ? "none" : fmt::format("{}", fmt::join(f.wrong_fields, ", ")),
            made_right.empty() ? "" : fmt::format(" ({} made right)", fmt::join(made_right, ", ")),
            r.stopped() ? ", not narrowed further" : ""));
}

}  // namespace mbstorm::netfuzz
