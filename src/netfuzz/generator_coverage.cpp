// Coverage-guided cases (mbstorm fuzz --coverage): mutations of the cases that reached new
// edges of the target. Fields take the constants the target was seen comparing its input
// against, so a check like `address == 0x1234 && value == 0xBEEF` is passed one field at a
// time: the first comparison passed is a new edge, that case joins the corpus, and its
// mutations try the second constant. Whatever the target's framing (MBAP, RTU, ASCII), the
// mutations change a frame's MBAP view (unit and PDU behind an MBAP header) and the frame is
// made again around it: a CRC or an LRC follows its PDU as an MBAP length does.
#include <algorithm>

#include <fmt/format.h>
#include <set>
#include <string>

#include "codec/limits.hpp"
#include "codec/mbap.hpp"
#include "netfuzz/generator.hpp"
#include "netfuzz/minimize.hpp"
#include "netfuzz/wire.hpp"

namespace mbstorm::netfuzz {
namespace {

namespace lim = codec::limits;

// One whole MBAP frame, its length field saying so: what coverage mutations change.
bool one_frame(const Step& s) {
    return s.op == Op::Send && s.bytes.size() > lim::kMbapHeader &&
           codec::load_be16(s.bytes.data() + 4) + 6u == s.bytes.size();
}

// A case's sends as the mutations see them: each send that is one whole request frame in
// `framing` turned into its MBAP view, and marked; the others left as they are.
std::vector<bool> to_mbap_views(Case& c, codec::Framing framing) {
    std::vector<bool> framed(c.steps.size(), false);
    for (std::size_t i = 0; i < c.steps.size(); ++i) {
        Step& s = c.steps[i];
        if (s.op != Op::Send) continue;
        if (framing == codec::Framing::Mbap) {
            framed[i] = one_frame(s);
            continue;
        }
        WireFrame f;
        if (cut_frame(s.bytes, framing, true, 0, f) != WireCut::Frame || f.size != s.bytes.size() ||
            !f.discard.empty())
            continue;
        s.bytes = std::move(f.mbap);
        framed[i] = true;
    }
    return framed;
}

// The marked sends framed in `framing` again.
void from_mbap_views(Case& c, const std::vector<bool>& framed, codec::Framing framing) {
    if (framing == codec::Framing::Mbap) return;
    for (std::size_t i = 0; i < c.steps.size(); ++i)
        if (framed[i]) c.steps[i].bytes = reframe(c.steps[i].bytes, framing);
}

// The function code of the first marked send (0 when none).
std::uint8_t first_function(const Case& c, const std::vector<bool>& framed) {
    for (std::size_t i = 0; i < c.steps.size(); ++i)
        if (framed[i]) return c.steps[i].bytes[lim::kMbapHeader];
    return 0;
}

// What a case sends, step by step: two cases with the same key are the same case.
std::string sends_key(const Case& c) {
    std::string key;
    for (const Step& s : c.steps) {
        key.append(s.bytes.begin(), s.bytes.end());
        key.push_back('|');
    }
    return key;
}

// The most recent entries are mutated more often: they are the frontier.
constexpr std::uint32_t kFrontier = 16;
constexpr std::size_t kMaxCompared = 4096;

}  // namespace

void Generator::add_to_corpus(const Case& c, const std::vector<Comparison>& comparisons,
                              std::uint32_t rarest_edge) {
    // A frame per send, so that a mutation or a solved comparison stays inside one frame and
    // its MBAP length can follow it.
    Case entry = split_frames(c, options_.framing);
    entry.number = 0;
    entry.cls = MutationClass::CoverageMutation;
    coverage_corpus_.push_back(entry);
    corpus_rare_edge_.push_back(rarest_edge);
    solve_comparisons(entry, comparisons);
}

namespace {

// Puts the other operand of `cmp` where the case's marked frames (MBAP views) carry one of
// them (big-endian, in a PDU); false when neither is there.
bool apply(Case& c, const std::vector<bool>& framed, const Comparison& cmp) {
    const std::size_t n = cmp.size == 1 ? 1 : 2;
    if (n == 2 && (cmp.a > 0xFFFF || cmp.b > 0xFFFF)) return false;
    for (std::size_t i = 0; i < c.steps.size(); ++i) {
        std::vector<std::uint8_t>& f = c.steps[i].bytes;
        if (!framed[i]) continue;
        for (std::size_t at = lim::kMbapHeader; at + n <= f.size(); ++at) {
            const std::uint64_t here = n == 1 ? f[at] : codec::load_be16(f.data() + at);
            const std::uint64_t to = here == cmp.a ? cmp.b : here == cmp.b ? cmp.a : here;
            if (to == here) continue;
            if (n == 1)
                f[at] = static_cast<std::uint8_t>(to);
            else
                codec::store_be16(f.data() + at, static_cast<std::uint16_t>(to));
            return true;
        }
    }
    return false;
}

}  // namespace

// A case per failed comparison whose operand the frames carry, and per run of up to three
// comparisons in a row (`a == X && b == Y && c == Z` may be one branch): at most kMaxSolved
// different ones per corpus entry. (A target's framing and its loops compare the same bytes
// many times over: without telling the cases apart, those used up the budget before the
// comparisons of the request handler, which come last.)
void Generator::solve_comparisons(const Case& c, const std::vector<Comparison>& comparisons) {
    constexpr std::size_t kMaxSolved = 96, kMaxRun = 3;
    Case view = c;
    const std::vector<bool> framed = to_mbap_views(view, options_.framing);
    std::set<std::string> made_already;
    std::size_t made = 0;
    std::vector<const std::uint32_t*> counts;
    for (const std::size_t k : rarest_first(comparisons, counts)) {
        if (made >= kMaxSolved) break;
        Case run = view;
        for (std::size_t i = k; i < std::min(comparisons.size(), k + kMaxRun); ++i) {
            if (!apply(run, framed, comparisons[i])) break;
            if (!made_already.insert(sends_key(run)).second) continue;
            Case solved = run;
            solved.function = first_function(run, framed);
            from_mbap_views(solved, framed, options_.framing);
            push_solved(std::move(solved), counts[k]);
            ++made;
        }
    }
}

// The indexes of `comparisons`, those fewest corpus entries made before first (a framing's or
// a loop's comparisons come with every case; a request handler's with few), and (`counts`)
// each one's count of entries that made it, kept up to date as more entries come (null when
// too many different comparisons are counted already); counted.
std::vector<std::size_t> Generator::rarest_first(const std::vector<Comparison>& comparisons,
                                                 std::vector<const std::uint32_t*>& counts) {
    constexpr std::size_t kMaxKnown = 1 << 20;
    std::vector<std::size_t> order(comparisons.size());
    std::vector<std::uint32_t> before(comparisons.size(), 0);
    counts.assign(comparisons.size(), nullptr);
    for (std::size_t i = 0; i < comparisons.size(); ++i) {
        const Comparison& c = comparisons[i];
        const std::string key = fmt::format("{}:{:x}:{:x}", c.size, c.a, c.b);
        auto it = comparisons_seen_.find(key);
        if (it == comparisons_seen_.end() && comparisons_seen_.size() < kMaxKnown)
            it = comparisons_seen_.emplace(key, 0).first;
        if (it != comparisons_seen_.end()) {
            before[i] = it->second++;
            counts[i] = &it->second;  // unordered_map nodes stay where they are
        }
        order[i] = i;
    }
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t x, std::size_t y) { return before[x] < before[y]; });
    return order;
}

void Generator::push_solved(Case c, const std::uint32_t* count) {
    solved_.push_back(Solved{count, solved_order_++, std::move(c)});
}

// The case of the comparison fewest entries have made by now, of equally rare ones the newest
// (a scan: the counts change as entries come, and a case run costs far more).
Case Generator::pop_solved() {
    const auto rarity = [](const Solved& s) { return s.count ? *s.count : 0u; };
    std::size_t best = 0;
    for (std::size_t i = 1; i < solved_.size(); ++i) {
        const std::uint32_t r = rarity(solved_[i]), b = rarity(solved_[best]);
        if (r < b || (r == b && solved_[i].order > solved_[best].order)) best = i;
    }
    Case c = std::move(solved_[best].c);
    solved_[best] = std::move(solved_.back());
    solved_.pop_back();
    return c;
}

void Generator::add_compared(const std::vector<std::uint16_t>& words,
                             const std::vector<std::uint8_t>& bytes) {
    for (std::uint16_t w : words)
        if (compared_words_.size() < kMaxCompared) compared_words_.push_back(w);
    for (std::uint8_t b : bytes)
        if (compared_bytes_.size() < 256) compared_bytes_.push_back(b);
}

std::uint16_t Generator::compared_word() {
    if (!compared_words_.empty() && !rng_.chance(4))
        return compared_words_[rng_.below(static_cast<std::uint32_t>(compared_words_.size()))];
    return word();
}

std::size_t Generator::pick_corpus_entry() {
    const auto n = static_cast<std::uint32_t>(coverage_corpus_.size());
    if (!rng_.chance(2)) return rng_.below(n);
    if (!edge_counts_) return n > kFrontier ? n - 1 - rng_.below(kFrontier) : rng_.below(n);
    // The entry of the rarest edge; of equally rare ones, the newest.
    std::size_t best = n - 1;
    for (std::size_t i = n; i-- > 0;)
        if (edge_counts_->cases_hitting(corpus_rare_edge_[i]) <
            edge_counts_->cases_hitting(corpus_rare_edge_[best]))
            best = i;
    return best;
}

void Generator::corpus_mutation(Case& out) {
    if (!solved_.empty()) {
        out = pop_solved();
        return;
    }
    out = coverage_corpus_[pick_corpus_entry()];
    out.cls = MutationClass::CoverageMutation;
    out.pipelinable = false;
    // One frame of the case (a sequence keeps its other steps as they were).
    const std::vector<bool> framed = to_mbap_views(out, options_.framing);
    std::vector<std::size_t> frames;
    for (std::size_t i = 0; i < out.steps.size(); ++i)
        if (framed[i]) frames.push_back(i);
    if (frames.empty()) return;
    std::vector<std::uint8_t>& f =
        out.steps[frames[rng_.below(static_cast<std::uint32_t>(frames.size()))]].bytes;
    for (std::uint32_t i = 0, stack = 1 + rng_.below(4); i < stack; ++i) mutate_frame(f);
    // The header follows the PDU (lying lengths are the mbap-length class's).
    codec::store_be16(f.data() + 4, static_cast<std::uint16_t>(f.size() - 6));
    out.function = f[lim::kMbapHeader];
    from_mbap_views(out, framed, options_.framing);
}

// One mutation of the PDU of MBAP frame `f` (its function code included).
void Generator::mutate_frame(std::vector<std::uint8_t>& f) {
    const auto pdu_size = static_cast<std::uint32_t>(f.size() - lim::kMbapHeader);
    const auto at = [&](std::uint32_t room) {
        return lim::kMbapHeader + rng_.below(pdu_size > room ? pdu_size - room : 1);
    };
    switch (rng_.below(8)) {
        case 0:
        case 1:
        case 2:  // a 16-bit field set to a compared constant (or a dictionary word)
            if (pdu_size >= 3) codec::store_be16(f.data() + 1 + at(2), compared_word());
            break;
        case 3: {  // a byte set to a compared constant
            const std::uint8_t b = compared_bytes_.empty()
                                       ? rng_.byte()
                                       : compared_bytes_[rng_.below(
                                             static_cast<std::uint32_t>(compared_bytes_.size()))];
            f[at(0)] = b;
            break;
        }
        case 4:  // a bit flip
            f[at(0)] ^= static_cast<std::uint8_t>(1u << rng_.below(8));
            break;
        case 5: {  // a 16-bit field a little more or less
            if (pdu_size < 3) break;
            const std::size_t i = 1 + at(2);
            const int delta = static_cast<int>(rng_.below(35)) - 17;
            codec::store_be16(f.data() + i,
                              static_cast<std::uint16_t>(codec::load_be16(f.data() + i) + delta));
            break;
        }
        case 6: {  // the tail of another entry's first frame
            Case other =
                coverage_corpus_[rng_.below(static_cast<std::uint32_t>(coverage_corpus_.size()))];
            const std::vector<bool> framed = to_mbap_views(other, options_.framing);
            for (std::size_t k = 0; k < other.steps.size(); ++k) {
                const Step& s = other.steps[k];
                if (!framed[k] || s.bytes.size() <= lim::kMbapHeader) continue;
                const std::size_t cut = at(0) + 1;
                const std::size_t from =
                    lim::kMbapHeader +
                    rng_.below(static_cast<std::uint32_t>(s.bytes.size() - lim::kMbapHeader));
                f.resize(cut);
                f.insert(f.end(), s.bytes.begin() + static_cast<std::ptrdiff_t>(from),
                         s.bytes.end());
                break;
            }
            break;
        }
        case 7:  // a random byte
            f[at(0)] = rng_.byte();
            break;
    }
    if (f.size() > lim::kMbapHeader + lim::kMaxPdu) f.resize(lim::kMbapHeader + lim::kMaxPdu);
}

}  // namespace mbstorm::netfuzz
