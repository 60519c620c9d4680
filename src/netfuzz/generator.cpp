#include "netfuzz/generator.hpp"

#include <algorithm>

#include "codec/bytes.hpp"
#include "codec/function_code.hpp"
#include "codec/limits.hpp"
#include "codec/mbap.hpp"
#include "codec/pdu.hpp"
#include "netfuzz/oracle.hpp"

namespace mbstorm::netfuzz {
namespace {

using Pdu = std::vector<std::uint8_t>;
namespace lim = codec::limits;

void put16(Pdu& p, std::uint16_t v) {
    p.push_back(static_cast<std::uint8_t>(v >> 8));
    p.push_back(static_cast<std::uint8_t>(v));
}

// The function codes the generator's own cases name (the stateful writes and their read-backs,
// the filter of restarts), by the codec's names; boundary cases come from the table.
constexpr std::uint8_t kReadCoils = codec::to_byte(codec::FunctionCode::ReadCoils);
constexpr std::uint8_t kReadHoldingRegisters =
    codec::to_byte(codec::FunctionCode::ReadHoldingRegisters);
constexpr std::uint8_t kWriteSingleCoil = codec::to_byte(codec::FunctionCode::WriteSingleCoil);
constexpr std::uint8_t kWriteSingleRegister =
    codec::to_byte(codec::FunctionCode::WriteSingleRegister);
constexpr std::uint8_t kDiagnostics = codec::to_byte(codec::FunctionCode::Diagnostics);
constexpr std::uint8_t kWriteMultipleCoils =
    codec::to_byte(codec::FunctionCode::WriteMultipleCoils);
constexpr std::uint8_t kWriteMultipleRegisters =
    codec::to_byte(codec::FunctionCode::WriteMultipleRegisters);
constexpr std::uint8_t kMaskWriteRegister = codec::to_byte(codec::FunctionCode::MaskWriteRegister);
constexpr std::uint8_t kReadWriteMultipleRegisters =
    codec::to_byte(codec::FunctionCode::ReadWriteMultipleRegisters);

Pdu pdu5(std::uint8_t fc, std::uint16_t a, std::uint16_t b) {
    Pdu p{fc};
    put16(p, a);
    put16(p, b);
    return p;
}

// Addresses worth trying for a request of `quantity` items: both ends of the space, the
// last start that fits, the first that wraps past 0xFFFF, and the sign boundary.
std::vector<std::uint16_t> addresses_for(std::uint32_t quantity) {
    std::vector<std::uint16_t> a = {0, 1, 0x7FFF, 0x8000, 0xFFFE, 0xFFFF};
    if (quantity > 0 && quantity <= 0x10000) {
        a.push_back(static_cast<std::uint16_t>(0x10000 - quantity));
        a.push_back(static_cast<std::uint16_t>(0x10000 - quantity + 1));
    }
    std::sort(a.begin(), a.end());
    a.erase(std::unique(a.begin(), a.end()), a.end());
    return a;
}

void add_reads(std::vector<Pdu>& out, std::uint8_t fc, std::uint16_t max) {
    const std::uint32_t qs[] = {0u, 1u, 2u, 7u, 8u, 9u, max - 1u, max, max + 1u, 0xFFFFu};
    for (std::uint32_t q : qs)
        for (std::uint16_t a : addresses_for(q))
            out.push_back(pdu5(fc, a, static_cast<std::uint16_t>(q)));
}

// FC0F/FC10: quantity, and byte counts that agree or disagree with it.
void add_multi_writes(std::vector<Pdu>& out, std::uint8_t fc, std::uint16_t max, bool coils) {
    const std::uint32_t qs[] = {0u, 1u, 2u, 8u, 9u, max - 1u, max, max + 1u, 0xFFFFu};
    for (std::uint32_t q : qs) {
        const std::uint32_t right = coils ? (q + 7) / 8 : 2 * q;
        std::vector<std::uint32_t> counts = {right, right + 1, 0};
        if (right > 0) counts.push_back(right - 1);
        for (std::uint32_t bc : counts) {
            const std::uint32_t room = lim::kMaxPdu - 6;
            const std::uint32_t data = std::min(bc, room);
            for (std::uint16_t a : {std::uint16_t{0}, std::uint16_t(0x10000 - std::max(q, 1u)),
                                    std::uint16_t(0x10000 - std::max(q, 1u) + 1)}) {
                Pdu p = pdu5(fc, a, static_cast<std::uint16_t>(q));
                p.push_back(static_cast<std::uint8_t>(std::min(bc, 255u)));
                for (std::uint32_t i = 0; i < data; ++i)
                    p.push_back(static_cast<std::uint8_t>(0xA5 ^ i));
                out.push_back(std::move(p));
            }
        }
    }
}

void add_file_records(std::vector<Pdu>& out, std::uint8_t fc, bool with_data) {
    struct Sub {
        std::uint8_t ref;
        std::uint16_t file, record, length;
    };
    const Sub subs[] = {{6, 1, 0, 1},      {6, 1, 9999, 1}, {6, 1, 10000, 1}, {6, 0, 0, 1},
                        {6, 0xFFFF, 0, 1}, {5, 1, 0, 1},    {7, 1, 0, 1},     {6, 1, 0, 0},
                        {6, 1, 9990, 20},  {6, 4, 0, 120},  {6, 5, 0, 1},     {0xFF, 1, 0, 1}};
    for (const Sub& s : subs) {
        for (int copies : {1, 2}) {
            Pdu body;
            for (int c = 0; c < copies; ++c) {
                body.push_back(s.ref);
                put16(body, s.file);
                put16(body, s.record);
                put16(body, s.length);
                if (with_data)
                    for (std::uint32_t i = 0; i < std::min<std::uint32_t>(s.length, 100) * 2u; ++i)
                        body.push_back(static_cast<std::uint8_t>(i));
            }
            if (body.size() > lim::kMaxPdu - 2) body.resize(lim::kMaxPdu - 2);
            for (int skew : {0, 1, -1}) {
                Pdu p{fc, static_cast<std::uint8_t>(body.size() + skew)};
                p.insert(p.end(), body.begin(), body.end());
                out.push_back(std::move(p));
            }
        }
    }
    out.push_back(Pdu{fc, 0});
    out.push_back(Pdu{fc, 0xFF});
}

void add_read_write_multiple(std::vector<Pdu>& out, std::uint8_t fc) {
    const std::uint32_t rqs[] = {0, 1, 125, 126};
    const std::uint32_t wqs[] = {0, 1, 121, 122};
    for (std::uint32_t rq : rqs) {
        for (std::uint32_t wq : wqs) {
            const std::uint16_t ra = 0x0100;
            // Overlaps of the write range with the read range: same start, inside, touching
            // the end, disjoint, and wrapping past 0xFFFF.
            const std::uint16_t was[] = {ra, static_cast<std::uint16_t>(ra + 1),
                                         static_cast<std::uint16_t>(ra + std::max(rq, 1u) - 1),
                                         0x0400, 0xFFFF};
            for (std::uint16_t wa : was) {
                for (int skew : {0, 1, -1}) {
                    const int bc = static_cast<int>(2 * wq) + skew;
                    if (bc < 0) continue;
                    Pdu p = pdu5(fc, ra, static_cast<std::uint16_t>(rq));
                    put16(p, wa);
                    put16(p, static_cast<std::uint16_t>(wq));
                    const int room = static_cast<int>(lim::kMaxPdu) - 10;
                    p.push_back(static_cast<std::uint8_t>(std::min(bc, 255)));
                    for (int i = 0; i < std::min(bc, room); ++i)
                        p.push_back(static_cast<std::uint8_t>(i * 7));
                    out.push_back(std::move(p));
                }
            }
        }
        // The read range itself at the top of the address space.
        Pdu p = pdu5(fc, static_cast<std::uint16_t>(0x10000 - std::max(rq, 1u) + 1),
                     static_cast<std::uint16_t>(rq));
        put16(p, 0);
        put16(p, 1);
        p.push_back(2);
        put16(p, 0x1234);
        out.push_back(std::move(p));
    }
}

void add_single_coil_writes(std::vector<Pdu>& out, std::uint8_t fc) {
    for (std::uint16_t a : {0, 1, 0x7FFF, 0x8000, 0xFFFF})
        for (std::uint16_t v : {0x0000, 0xFF00, 0x0001, 0x00FF, 0xFFFF, 0xFF01, 0x8000})
            out.push_back(pdu5(fc, a, v));
}

void add_single_register_writes(std::vector<Pdu>& out, std::uint8_t fc) {
    for (std::uint16_t a : {0, 1, 0x7FFF, 0x8000, 0xFFFF})
        for (std::uint16_t v : {0x0000, 0xFFFF, 0x8000, 0x7FFF}) out.push_back(pdu5(fc, a, v));
}

// The serial-line status requests (FC07, 0B, 0C, 11): bare, and with a stray byte.
void add_status_request(std::vector<Pdu>& out, std::uint8_t fc) {
    out.push_back(Pdu{fc});
    out.push_back(Pdu{fc, 0x00});
}

// FC08: every defined sub-function and some undefined ones, with right and wrong data sizes,
// and a long echo. 0x0001 (restart) and 0x0004 (listen-only) are left out: real devices may
// legitimately drop the connection or go silent.
void add_diagnostics(std::vector<Pdu>& out, std::uint8_t fc) {
    for (std::uint16_t sub :
         {0x0000, 0x0002, 0x0003, 0x000A, 0x000B, 0x000C, 0x000D, 0x000E, 0x000F, 0x0010, 0x0011,
          0x0012, 0x0013, 0x0014, 0x0015, 0x00FF, 0xFFFF}) {
        for (int words : {0, 1, 2}) {
            Pdu p{fc};
            put16(p, sub);
            for (int i = 0; i < words; ++i) put16(p, sub == 0 ? 0xA55A : 0x0000);
            out.push_back(std::move(p));
        }
    }
    Pdu echo{fc, 0x00, 0x00};
    for (int i = 0; i < 250; ++i) echo.push_back(static_cast<std::uint8_t>(i));
    out.push_back(echo);
}

void add_mask_writes(std::vector<Pdu>& out, std::uint8_t fc) {
    for (std::uint16_t a : {0, 1, 0x7FFF, 0xFFFF}) {
        for (std::uint16_t m : {0x0000, 0xFFFF, 0x00FF}) {
            Pdu p = pdu5(fc, a, m);
            put16(p, static_cast<std::uint16_t>(~m));
            out.push_back(std::move(p));
        }
    }
}

void add_fifo_reads(std::vector<Pdu>& out, std::uint8_t fc) {
    for (std::uint16_t a : {0, 1, 0x7FFF, 0xFFE0, 0xFFFE, 0xFFFF}) {
        Pdu p{fc};
        put16(p, a);
        out.push_back(std::move(p));
    }
}

// FC2B: every MEI type worth trying; for 0E every read device id code and object ids at the
// edges of the basic, regular, reserved and extended ranges.
void add_encapsulated(std::vector<Pdu>& out, std::uint8_t fc) {
    for (std::uint8_t code : {0, 1, 2, 3, 4, 5, 0xFF})
        for (std::uint8_t obj : {0x00, 0x01, 0x02, 0x03, 0x06, 0x07, 0x7F, 0x80, 0xFF})
            out.push_back(Pdu{fc, codec::kMeiReadDeviceId, code, obj});
    const std::uint8_t basic_objects = 0x01;  // read device id code 01
    for (std::uint8_t mei : {0x00, 0x0D, 0x0F, 0xFF})
        out.push_back(Pdu{fc, mei, basic_objects, 0x00});
    out.push_back(Pdu{fc});
    out.push_back(Pdu{fc, codec::kMeiReadDeviceId});
}

// Every function code 0-255: bare, and with a plausible read body.
void add_every_function_code(std::vector<Pdu>& out) {
    for (unsigned fc = 0; fc < 256; ++fc) {
        const auto b = static_cast<std::uint8_t>(fc);
        if (!codec::is_supported_function(b)) out.push_back(Pdu{b});
        out.push_back(pdu5(b, 0, 1));
    }
}

// The boundary requests of function `f`, by its request shape: a code of a known shape gets
// them with no change here, a new shape is named by -Wswitch.
void add_boundaries(std::vector<Pdu>& out, const codec::FunctionInfo& f) {
    using codec::RequestShape;
    const std::uint8_t fc = codec::to_byte(f.code);
    switch (f.request) {
        case RequestShape::AddressQuantity:
            return add_reads(out, fc, f.quantity.max);
        case RequestShape::SingleCoil:
            return add_single_coil_writes(out, fc);
        case RequestShape::SingleRegister:
            return add_single_register_writes(out, fc);
        case RequestShape::FunctionOnly:
            return add_status_request(out, fc);
        case RequestShape::SubFunction:
            return add_diagnostics(out, fc);
        case RequestShape::MultipleCoils:
            return add_multi_writes(out, fc, f.quantity.max, true);
        case RequestShape::MultipleRegisters:
            return add_multi_writes(out, fc, f.quantity.max, false);
        case RequestShape::FileRecords:
            return add_file_records(out, fc, f.writes);
        case RequestShape::MaskWrite:
            return add_mask_writes(out, fc);
        case RequestShape::ReadWriteRegisters:
            return add_read_write_multiple(out, fc);
        case RequestShape::FifoPointer:
            return add_fifo_reads(out, fc);
        case RequestShape::MeiTransport:
            return add_encapsulated(out, fc);
    }
}

// Where a shape's boundary requests come in the list: the order it has always had (reads,
// single writes, status, diagnostics, multiple writes, ...), so that a seed keeps giving the
// same cases.
int boundary_group(codec::RequestShape shape) {
    using codec::RequestShape;
    switch (shape) {
        case RequestShape::AddressQuantity:
            return 0;
        case RequestShape::SingleCoil:
        case RequestShape::SingleRegister:
            return 1;
        case RequestShape::FunctionOnly:
            return 2;
        case RequestShape::SubFunction:
            return 3;
        case RequestShape::MultipleCoils:
        case RequestShape::MultipleRegisters:
            return 4;
        case RequestShape::FileRecords:
            return 5;
        case RequestShape::MaskWrite:
            return 6;
        case RequestShape::ReadWriteRegisters:
            return 7;
        case RequestShape::FifoPointer:
            return 8;
        case RequestShape::MeiTransport:
            return 9;
    }
    return 0;
}
constexpr int kBoundaryGroups = 10;

}  // namespace

std::vector<std::vector<std::uint8_t>> structured_pdus() {
    std::vector<Pdu> out;
    for (int group = 0; group < kBoundaryGroups; ++group)
        for (const codec::FunctionInfo& f : codec::public_functions())
            if (boundary_group(f.request) == group) add_boundaries(out, f);
    add_every_function_code(out);
    return out;
}

const std::vector<std::uint16_t>& interesting_words() {
    static const std::vector<std::uint16_t> words = {
        0x0000, 0x0001, 0x0002, 0x007F, 0x0080, 0x00FF, 0x0100, 0x7FFE, 0x7FFF, 0x8000,
        0x8001, 0xFF00, 0xFFFE, 0xFFFF, 0x5555, 0xAAAA, 0xDEAD, 0xBEEF, 0xCAFE, 0x1234};
    return words;
}

Generator::Generator(const GeneratorOptions& options)
    : options_(options), rng_(options.seed), seeds_(structured_pdus()) {
    // Seed-dependent order, so that different seeds explore in different orders.
    for (std::size_t i = seeds_.size(); i > 1; --i)
        std::swap(seeds_[i - 1], seeds_[rng_.below(static_cast<std::uint32_t>(i))]);
    // Coverage first, even on a slow target: one valid request of every function code, then
    // one invalid one of each, then the rest in the shuffled order.
    {
        std::array<int, 256> valid_seen{}, invalid_seen{};
        std::vector<int> rank(seeds_.size(), 2);
        for (std::size_t i = 0; i < seeds_.size(); ++i) {
            codec::Request r;
            const bool ok = codec::decode_request(seeds_[i], r).ok();
            auto& seen = ok ? valid_seen : invalid_seen;
            if (!seen[seeds_[i][0]]++) rank[i] = ok ? 0 : 1;
        }
        std::vector<std::size_t> order(seeds_.size());
        for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
        std::stable_sort(order.begin(), order.end(),
                         [&](std::size_t a, std::size_t b) { return rank[a] < rank[b]; });
        std::vector<std::vector<std::uint8_t>> sorted;
        sorted.reserve(seeds_.size());
        for (std::size_t i : order) sorted.push_back(std::move(seeds_[i]));
        seeds_ = std::move(sorted);
    }
    tid_ = rng_.u16();
    std::array<int, 256> function_slot;
    function_slot.fill(-1);
    for (std::size_t i = 0; i < seeds_.size(); ++i) {
        codec::Request r;
        const std::uint8_t fc = seeds_[i][0];
        if (codec::decode_request(seeds_[i], r).ok()) {
            valid_seeds_.push_back(i);
            corpus_.push_back(seeds_[i]);
        } else {
            invalid_seeds_.push_back(i);
        }
        if (function_slot[fc] < 0) {
            function_slot[fc] = static_cast<int>(seeds_by_function_.size());
            seeds_by_function_.emplace_back();
        }
        seeds_by_function_[static_cast<std::size_t>(function_slot[fc])].push_back(i);
    }
    for (const auto& token : options_.dict_tokens)
        if (!token.empty() && token.size() <= lim::kMaxPdu) corpus_.push_back(token);
}

std::uint16_t Generator::word() {
    if (!options_.dict_words.empty() && rng_.chance(2))
        return options_
            .dict_words[rng_.below(static_cast<std::uint32_t>(options_.dict_words.size()))];
    if (rng_.chance(2)) {
        const auto& words = interesting_words();
        return words[rng_.below(static_cast<std::uint32_t>(words.size()))];
    }
    return rng_.u16();
}

std::uint16_t Generator::state_address(std::uint16_t room) {
    const StateRange& st = options_.state;
    const std::uint32_t span = std::min<std::uint32_t>(st.span, 0x10000u - st.base);
    if (span <= room) return st.base;
    if (st.whole_map()) {
        // The user's own addresses first, then the edges of the map, then anywhere.
        std::uint32_t a = rng_.chance(2) ? word() : rng_.u16();
        return static_cast<std::uint16_t>(std::min<std::uint32_t>(a, 0x10000u - room));
    }
    return static_cast<std::uint16_t>(st.base + rng_.below(span - room));
}

void Generator::deprioritise(std::uint8_t function, MutationClass cls) {
    const std::size_t bit =
        function * static_cast<std::size_t>(MutationClass::Count) + static_cast<std::size_t>(cls);
    deprioritised_[bit / 32] |= 1u << (bit % 32);
}

bool Generator::deprioritised(const Case& c) const noexcept {
    const std::size_t bit = c.function * static_cast<std::size_t>(MutationClass::Count) +
                            static_cast<std::size_t>(c.cls);
    return (deprioritised_[bit / 32] >> (bit % 32)) & 1u;
}

std::vector<std::uint8_t> Generator::frame(const std::vector<std::uint8_t>& pdu,
                                           std::uint8_t unit) {
    std::vector<std::uint8_t> f = frame_pdu(pdu, tid(), unit);
    // However the PDU was made (a mutation, random bytes), never diagnostics 0001 (restart)
    // or 0004 (listen-only): a device may rightly go quiet after either. Echo (0000) instead.
    const bool restart_or_listen_only = pdu.size() >= 3 && pdu[0] == kDiagnostics &&
                                        pdu[1] == 0x00 && (pdu[2] == 0x01 || pdu[2] == 0x04);
    if (restart_or_listen_only) f[lim::kMbapHeader + 2] = 0x00;
    return f;
}

const std::vector<std::uint8_t>& Generator::next_seed() {
    const auto& s = seeds_[seed_cursor_];
    seed_cursor_ = (seed_cursor_ + 1) % seeds_.size();
    return s;
}

const std::vector<std::uint8_t>& Generator::valid_seed() {
    return seeds_[valid_seeds_[rng_.below(static_cast<std::uint32_t>(valid_seeds_.size()))]];
}

void Generator::next(Case& out) {
    for (int attempt = 0; attempt < 8; ++attempt) {
        out.steps.clear();
        out.pipelinable = false;
        if (options_.naive) {
            naive(out);
            return;
        }
        if (!solved_.empty() || (!coverage_corpus_.empty() && rng_.chance(2))) {
            corpus_mutation(out);  // as the target ran it: not relocated or reframed
            return;
        }
        const std::uint32_t roll = rng_.below(1000);
        // With a model, a share of the cases is aimed inside the device's map (most of them
        // on a target that pauses after exceptions, so that its run is not spent waiting).
        const std::uint32_t aimed = !has_model()                                ? 0
                                    : options_.model->pauses_after_exceptions() ? 700
                                                                                : 400;
        const std::uint32_t rest =
            roll < options_.isolated_per_mille ? roll : (roll - options_.isolated_per_mille) % 1000;
        if (roll < options_.isolated_per_mille)
            isolated(out);
        else if (rest < aimed / 5)
            map_edge(out);
        else if (rest < aimed)
            in_map(out);
        else if (rest < aimed + 150)
            mutate_recorded(out);
        else
            structured(out);
        // A class that already crashed or hung the target gets 1 draw in 16.
        if (!deprioritised(out) || rng_.chance(16)) break;
    }
    for (Step& s : out.steps)
        if (s.op == Op::Send && out.cls != MutationClass::StatefulSame &&
            out.cls != MutationClass::StatefulCross)
            relocate_writes(s.bytes.data(), s.bytes.size(), options_.state);
    adapt_to_framing(out);
}

void Generator::naive(Case& out) {
    const std::uint32_t n = 1 + rng_.below(lim::kMaxPdu);
    std::vector<std::uint8_t> pdu(n);
    for (auto& b : pdu) b = rng_.byte();
    out.cls = MutationClass::NaiveRandom;
    out.function = pdu[0];
    out.steps.push_back(Step{Op::Send, 0, 0, 0, frame(pdu, options_.unit)});
    out.pipelinable = true;
}

void Generator::structured(Case& out, MutationClass forced) {
    const std::uint32_t roll = rng_.below(100);
    if (forced == MutationClass::Count && roll < 5) forced = MutationClass::UnitId;
    // Unit ids walk pairwise with function codes: every unit-id class meets every function
    // code's boundary cases.
    const std::uint8_t units[] = {0x00, 0xF7, 0xFF, 0x02, 0x00};
    const std::size_t n_units = sizeof units;
    std::size_t unit_class = 0;
    const std::vector<std::uint8_t>* chosen = nullptr;
    if (forced == MutationClass::UnitId) {
        const std::size_t k = unit_cursor_++;
        unit_class = k % n_units;
        const auto& list = seeds_by_function_[(k / n_units) % seeds_by_function_.size()];
        chosen = &seeds_[list[rng_.below(static_cast<std::uint32_t>(list.size()))]];
    }
    const auto& pdu = chosen ? *chosen : next_seed();
    out.function = pdu[0];
    codec::Request r;
    const auto status = codec::decode_request(pdu, r);
    out.cls = status.ok() ? MutationClass::ValidLimits
              : status.error == codec::CodecError::UnsupportedFunction
                  ? MutationClass::UnknownFunction
                  : MutationClass::InvalidValues;
    out.pipelinable = true;
    std::uint8_t unit = options_.unit;
    if (forced == MutationClass::Count) {
        if (roll < 10)
            forced = MutationClass::ProtocolId;
        else if (roll < 15)
            forced = MutationClass::TrailingBytes;
        else if (roll < 20)
            forced = MutationClass::Coalesced;
    }
    if (forced == MutationClass::UnitId) {
        unit = unit_class + 1 == n_units ? rng_.byte() : units[unit_class];  // last: random
        out.cls = MutationClass::UnitId;
    }
    std::vector<std::uint8_t> f = frame(pdu, unit);
    if (forced == MutationClass::ProtocolId) {
        const std::uint16_t pids[] = {0x0001, 0x0100, 0x8000, 0xFFFF};
        codec::store_be16(f.data() + 2, rng_.pick(pids));
        out.cls = MutationClass::ProtocolId;
    } else if (forced == MutationClass::TrailingBytes && f.size() < lim::kMaxTcpAdu) {
        const std::uint32_t extra = 1 + rng_.below(static_cast<std::uint32_t>(
                                            std::min<std::size_t>(4, lim::kMaxTcpAdu - f.size())));
        for (std::uint32_t i = 0; i < extra; ++i) f.push_back(rng_.byte());
        codec::store_be16(f.data() + 4, static_cast<std::uint16_t>(f.size() - 6));
        out.cls = MutationClass::TrailingBytes;
    } else if (forced == MutationClass::Coalesced) {
        const std::uint32_t n = 2 + rng_.below(15);
        for (std::uint32_t i = 0; i < n; ++i) {
            auto more = frame(next_seed(), options_.unit);
            f.insert(f.end(), more.begin(), more.end());
        }
        out.cls = MutationClass::Coalesced;
    }
    out.steps.push_back(Step{Op::Send, 0, 0, 0, std::move(f)});
}

void Generator::mutate_recorded(Case& out) {
    std::vector<std::uint8_t> pdu = corpus_[rng_.below(static_cast<std::uint32_t>(corpus_.size()))];
    const auto& other = corpus_[rng_.below(static_cast<std::uint32_t>(corpus_.size()))];
    const std::uint32_t kind = rng_.below(7);
    const std::uint8_t interesting[] = {0x00, 0x01, 0x7F, 0x80, 0xFE, 0xFF};
    switch (kind) {
        case 0:  // bit flips
            for (std::uint32_t i = 0, n = 1 + rng_.below(3); i < n; ++i)
                pdu[rng_.below(static_cast<std::uint32_t>(pdu.size()))] ^=
                    static_cast<std::uint8_t>(1u << rng_.below(8));
            break;
        case 1:  // an interesting byte value
            pdu[rng_.below(static_cast<std::uint32_t>(pdu.size()))] = rng_.pick(interesting);
            break;
        case 2: {  // splice: head of one request, tail of another
            const std::uint32_t cut = rng_.below(static_cast<std::uint32_t>(pdu.size()) + 1);
            const std::uint32_t from = rng_.below(static_cast<std::uint32_t>(other.size()) + 1);
            pdu.resize(cut);
            pdu.insert(pdu.end(), other.begin() + from, other.end());
            break;
        }
        case 3: {  // field splice: a 16-bit field copied at the same offset
            if (pdu.size() >= 3 && other.size() >= 3) {
                const std::uint32_t at =
                    1 +
                    rng_.below(static_cast<std::uint32_t>(std::min(pdu.size(), other.size()) - 2));
                pdu[at] = other[at];
                pdu[at + 1] = other[at + 1];
            }
            break;
        }
        case 6:  // a 16-bit field set to an interesting or dictionary word
            if (pdu.size() >= 3) {
                const std::uint32_t at =
                    1 + 2 * rng_.below(static_cast<std::uint32_t>((pdu.size() - 1) / 2));
                codec::store_be16(pdu.data() + at, word());
            }
            break;
        case 4:  // insert a byte
            pdu.insert(pdu.begin() + 1 + rng_.below(static_cast<std::uint32_t>(pdu.size())),
                       rng_.byte());
            break;
        default:  // drop a byte (never the function code)
            if (pdu.size() > 1)
                pdu.erase(pdu.begin() + 1 + rng_.below(static_cast<std::uint32_t>(pdu.size() - 1)));
            break;
    }
    if (pdu.empty()) pdu.push_back(kReadHoldingRegisters);
    if (pdu.size() > lim::kMaxPdu) pdu.resize(lim::kMaxPdu);
    out.cls = MutationClass::RecordedMutation;
    out.function = pdu[0];
    out.pipelinable = true;
    out.steps.push_back(Step{Op::Send, 0, 0, 0, frame(pdu, options_.unit)});
}

void Generator::isolated(Case& out) {
    // With a model, stateful cases write where the device keeps data: twice as many of them,
    // and on a target that pauses after exceptions (whose transport cases mostly wait out its
    // pauses) four times as many.
    const std::uint32_t stateful_share = !has_model()                                ? 27
                                         : options_.model->pauses_after_exceptions() ? 108
                                                                                     : 54;
    const std::uint32_t pick = rng_.below(100 + stateful_share - 27);
    if (pick < stateful_share) {
        stateful(out, pick >= stateful_share * 15 / 27);
        return;
    }
    const std::uint32_t roll = pick - (stateful_share - 27);
    if (roll < 35) {  // special transaction ids, twice the same on one connection
        const std::uint16_t tids[] = {0x0000, 0x00FF, 0x0100, 0x7FFF, 0x8000, 0xFFFF};
        const auto& pdu = valid_seed();
        auto f = frame(pdu, options_.unit);
        codec::store_be16(f.data(), rng_.pick(tids));
        out.cls = MutationClass::TransactionId;
        out.function = pdu[0];
        out.steps.push_back(Step{Op::Send, 0, 0, 0, f});
        if (rng_.chance(2)) {
            out.steps.push_back(Step{Op::Await, 0, 0, 0, {}});
            out.steps.push_back(Step{Op::Send, 0, 0, 0, f});
        }
        return;
    }
    if (roll < 41) {
        burst_split(out);
        return;
    }
    if (roll < 83 && roll >= 77) {  // a request owed an exception, then another client probes
        const auto& pdu =
            seeds_[invalid_seeds_[rng_.below(static_cast<std::uint32_t>(invalid_seeds_.size()))]];
        out.cls = MutationClass::ExceptionStall;
        out.function = pdu[0];
        out.steps.push_back(Step{Op::Send, 0, 0, 0, frame(pdu, options_.unit)});
        out.steps.push_back(Step{Op::Await, 0, 0, 0, {}});
        out.steps.push_back(Step{Op::SideProbe, 0, 0, 0, {}});
        return;
    }
    mangled_frame(out, roll);
}

// A valid frame delivered the wrong way (`roll` in 55..99 picks how): split, lying about its
// length, cut short, half-closed, held, dripped, or a flood of connections instead.
void Generator::mangled_frame(Case& out, std::uint32_t roll) {
    const auto& pdu = valid_seed();
    auto f = frame(pdu, options_.unit);
    out.function = pdu[0];
    if (roll < 55) {  // split at every offset, in turn, with small gaps
        out.cls = MutationClass::Split;
        const std::uint32_t at = 1 + split_cursor_++ % static_cast<std::uint32_t>(f.size() - 1);
        const std::uint32_t gaps[] = {0, 50, 200, 1000};
        out.steps.push_back(Step{Op::Send, 0, 0, 0, {f.begin(), f.begin() + at}});
        out.steps.push_back(Step{Op::Send, 0, rng_.pick(gaps), 0, {f.begin() + at, f.end()}});
        return;
    }
    if (roll < 60) {  // MBAP length field lies
        out.cls = MutationClass::MbapLength;
        const std::uint16_t actual = static_cast<std::uint16_t>(f.size() - 6);
        const std::uint16_t lengths[] = {0,
                                         1,
                                         2,
                                         255,
                                         0xFFFF,
                                         static_cast<std::uint16_t>(actual - 1),
                                         static_cast<std::uint16_t>(actual + 1),
                                         254};
        codec::store_be16(f.data() + 4, rng_.pick(lengths));
        out.steps.push_back(Step{Op::Send, 0, 0, 0, std::move(f)});
        return;
    }
    if (roll < 64) {  // truncated frame: the header promises more, then half-close
        out.cls = MutationClass::Truncated;
        f.resize(lim::kMbapHeader + rng_.below(static_cast<std::uint32_t>(pdu.size())));
        out.steps.push_back(Step{Op::Send, 0, 0, 0, std::move(f)});
        out.steps.push_back(Step{Op::ShutdownWrite, 0, 0, 0, {}});
        return;
    }
    if (roll < 68) {  // half-close after a partial frame (possibly inside the header)
        out.cls = MutationClass::HalfClose;
        f.resize(1 + rng_.below(static_cast<std::uint32_t>(f.size() - 1)));
        out.steps.push_back(Step{Op::Send, 0, 0, 0, std::move(f)});
        out.steps.push_back(Step{Op::ShutdownWrite, 0, 0, 0, {}});
        return;
    }
    if (roll < 73) {  // complete frames, then half-close: each is still owed its answer
        out.cls = MutationClass::HalfCloseAnswered;
        for (std::uint32_t i = 0, n = rng_.below(4); i < n; ++i) {
            auto more = frame(valid_seed(), options_.unit);
            f.insert(f.end(), more.begin(), more.end());
        }
        out.steps.push_back(Step{Op::Send, 0, 0, 0, std::move(f)});
        out.steps.push_back(Step{Op::ShutdownWrite, 0, 0, 0, {}});
        return;
    }
    slow_frame(out, roll, std::move(f));
}

// A started frame held open while another client probes, dripped a byte at a time, or (no
// frame at all) a flood of connections.
void Generator::slow_frame(Case& out, std::uint32_t roll, std::vector<std::uint8_t> f) {
    if (roll < 77) {  // a started frame held open while another client probes
        out.cls = MutationClass::PartialHold;
        const std::uint32_t at = 1 + rng_.below(static_cast<std::uint32_t>(f.size() - 1));
        out.steps.push_back(Step{Op::Send, 0, 0, 0, {f.begin(), f.begin() + at}});
        // Half the time the piece sits idle first: some servers give up waiting on a started
        // header only after a while, and then block on it.
        const std::uint32_t idle_us = rng_.chance(2) ? 150'000 : 0;
        out.steps.push_back(Step{Op::SideProbe, 0, idle_us, 0, {}});
        out.steps.push_back(Step{Op::Send, 0, 0, 0, {f.begin() + at, f.end()}});
        return;
    }
    if (roll < 95) {  // slow drip, one byte per send
        out.cls = MutationClass::Drip;
        // The header and the start of the PDU one byte at a time, then the rest.
        const std::size_t dripped = std::min<std::size_t>(f.size(), 12);
        for (std::size_t i = 0; i < dripped; ++i)
            out.steps.push_back(Step{Op::Send, 0, i ? 100u : 0u, 0, {f[i]}});
        if (dripped < f.size())
            out.steps.push_back(Step{Op::Send, 0, 100u, 0, {f.begin() + 12, f.end()}});
        return;
    }
    out.cls = MutationClass::Flood;
    out.function = 0;
    out.steps.push_back(Step{Op::Flood, 0, 0, static_cast<std::uint16_t>(8 + rng_.below(25)), {}});
}

// A pipelined burst of valid frames cut at one byte offset (walked in turn over the whole
// burst, so every offset of every frame comes up), the rest coalesced with the frames after
// it, with a gap of up to tens of milliseconds between the two sends.
void Generator::burst_split(Case& out) {
    out.cls = MutationClass::BurstSplit;
    std::vector<std::uint8_t> burst;
    const std::uint32_t n = 3 + rng_.below(6);
    for (std::uint32_t i = 0; i < n; ++i) {
        const auto& pdu = valid_seed();
        if (i == 0) out.function = pdu[0];
        auto f = frame(pdu, options_.unit);
        burst.insert(burst.end(), f.begin(), f.end());
    }
    const std::uint32_t at = 1 + burst_cursor_++ % static_cast<std::uint32_t>(burst.size() - 1);
    const std::uint32_t gaps[] = {0, 200, 2000, 10000, 40000};
    out.steps.push_back(Step{Op::Send, 0, 0, 0, {burst.begin(), burst.begin() + at}});
    out.steps.push_back(Step{Op::Send, 0, rng_.pick(gaps), 0, {burst.begin() + at, burst.end()}});
}

void Generator::stateful(Case& out, bool cross) {
    out.cls = cross ? MutationClass::StatefulCross : MutationClass::StatefulSame;
    const std::uint8_t writes[] = {kWriteSingleCoil,        kWriteSingleRegister,
                                   kWriteMultipleCoils,     kWriteMultipleRegisters,
                                   kWriteMultipleRegisters, kReadWriteMultipleRegisters,
                                   kMaskWriteRegister};
    const std::uint8_t fc = rng_.pick(writes);
    out.function = fc;
    // Where the device keeps data when its map is known; else the state range.
    const bool coil_write = fc == kWriteSingleCoil || fc == kWriteMultipleCoils;
    const std::uint16_t base = has_model() ? model_address(coil_write, 0) : state_address(130);
    const std::uint32_t room = has_model() ? map_room(coil_write, base) : 0x10000;
    std::uint16_t qty = 1;
    bool coils = false;
    const std::vector<std::uint8_t> w = stateful_write(out, fc, base, room, qty, coils);
    out.steps.push_back(Step{Op::Send, 0, 0, 0, frame(w, options_.unit)});
    out.steps.push_back(Step{Op::Await, 0, 0, 0, {}});
    read_back(out, cross, fc, base, qty, coils);
}

// The write of a stateful case at `base` (steps before it, if it needs any, go to `out`):
// its PDU, the items it writes and whether they are coils.
std::vector<std::uint8_t> Generator::stateful_write(Case& out, std::uint8_t fc, std::uint16_t base,
                                                    std::uint32_t room, std::uint16_t& qty,
                                                    bool& coils) {
    codec::Request w;
    w.function = fc;
    w.address = base;
    std::vector<std::uint8_t> payload;
    std::vector<std::uint16_t> registers;
    using FC = codec::FunctionCode;
    switch (static_cast<FC>(fc)) {
        case FC::WriteSingleCoil:
            coils = true;
            w.value = rng_.chance(2) ? lim::kCoilOn : lim::kCoilOff;
            break;
        case FC::WriteSingleRegister:
            w.value = word();
            break;
        case FC::WriteMultipleCoils:
            coils = true;
            qty = static_cast<std::uint16_t>(
                1 + rng_.below(std::min<std::uint32_t>(room, lim::kMaxWriteCoils)));
            w.quantity = qty;
            for (int i = 0; i < (qty + 7) / 8; ++i) payload.push_back(rng_.byte());
            break;
        case FC::WriteMultipleRegisters:
            qty = static_cast<std::uint16_t>(
                1 + rng_.below(std::min<std::uint32_t>(room, lim::kMaxWriteRegisters)));
            w.quantity = qty;
            for (int i = 0; i < qty; ++i) registers.push_back(word());
            payload = register_bytes(registers);
            break;
        case FC::ReadWriteMultipleRegisters:
            qty = static_cast<std::uint16_t>(
                1 + rng_.below(std::min<std::uint32_t>(room, lim::kMaxRwWriteRegisters)));
            read_write_over(out, w, payload, room, qty);
            break;
        case FC::MaskWriteRegister: {  // after a plain write, so the old value is known
            codec::Request pre;
            pre.function = kWriteSingleRegister;
            pre.address = base;
            pre.value = word();
            out.steps.push_back(Step{Op::Send, 0, 0, 0, frame(encode_pdu(pre), options_.unit)});
            out.steps.push_back(Step{Op::Await, 0, 0, 0, {}});
            w.and_mask = word();
            w.or_mask = word();
            break;
        }
        case FC::ReadCoils:  // not among the writes a stateful case picks
        case FC::ReadDiscreteInputs:
        case FC::ReadHoldingRegisters:
        case FC::ReadInputRegisters:
        case FC::ReadExceptionStatus:
        case FC::Diagnostics:
        case FC::GetCommEventCounter:
        case FC::GetCommEventLog:
        case FC::ReportServerId:
        case FC::ReadFileRecord:
        case FC::WriteFileRecord:
        case FC::ReadFifoQueue:
        case FC::EncapsulatedInterface:
            break;
    }
    w.payload = payload;
    return encode_pdu(w);
}

// FC 17's request `w` (its address the written block's `base`): the write of `qty` registers
// there, its read part over a range overlapping them, the values in `payload`. Reads back in
// the same request, then again separately (read_back).
void Generator::read_write_over(Case& out, codec::Request& w, std::vector<std::uint8_t>& payload,
                                std::uint32_t room, std::uint16_t qty) {
    const std::uint16_t base = w.address;
    const std::uint16_t rq = static_cast<std::uint16_t>(
        1 + rng_.below(std::min<std::uint32_t>(room, lim::kMaxRwReadRegisters)));
    w.address = static_cast<std::uint16_t>(base + rng_.below(qty));
    const std::uint32_t end =
        std::min<std::uint32_t>(0x10000u, std::uint32_t{options_.state.base} + options_.state.span);
    w.quantity = static_cast<std::uint16_t>(
        std::max<std::uint32_t>(1, std::min<std::uint32_t>(rq, end - base - qty)));
    w.write_address = base;
    w.write_quantity = qty;
    // First the complement of what it will write, so that its read part shows whether
    // the write came first however often the case runs (a rerun would otherwise find
    // the values already there).
    std::vector<std::uint16_t> values, complement;
    for (int i = 0; i < qty; ++i) {
        values.push_back(word());
        complement.push_back(static_cast<std::uint16_t>(~values.back()));
    }
    payload = register_bytes(values);
    const std::vector<std::uint8_t> complement_bytes = register_bytes(complement);
    codec::Request pre;
    pre.function = kWriteMultipleRegisters;
    pre.address = base;
    pre.quantity = qty;
    pre.payload = complement_bytes;
    out.steps.push_back(Step{Op::Send, 0, 0, 0, frame(encode_pdu(pre), options_.unit)});
    out.steps.push_back(Step{Op::Await, 0, 0, 0, {}});
}

// Reads a stateful write back: its exact range and one straddling its start, on the writer's
// connection (or the other one, `cross`), and on the other one too; FC 17 reads registers.
void Generator::read_back(Case& out, bool cross, std::uint8_t fc, std::uint16_t base,
                          std::uint16_t qty, bool coils) {
    const std::uint8_t reader = cross ? 1 : 0;
    // Read back: the exact range, and a range straddling its start.
    const std::uint16_t max = coils ? lim::kMaxReadBits : lim::kMaxReadRegisters;
    const std::uint16_t n = std::min(qty, max);
    out.steps.push_back(
        Step{Op::Send, reader, 0, 0,
             frame(pdu5(coils ? kReadCoils : kReadHoldingRegisters, base, n), options_.unit)});
    if (fc == kMaskWriteRegister) {
        // The mask write's result depends on the old value (written above): read it too.
        out.steps.back().bytes = frame(pdu5(kReadHoldingRegisters, base, 1), options_.unit);
    }
    const std::uint16_t before = static_cast<std::uint16_t>(
        base - std::min<std::uint32_t>(3, base - std::min(base, options_.state.base)));
    const std::uint16_t span = static_cast<std::uint16_t>(
        std::min<std::uint32_t>({std::uint32_t{n} + 3, max, 0x10000u - before}));
    out.steps.push_back(
        Step{Op::Send, reader, 0, 0,
             frame(pdu5(coils ? kReadCoils : kReadHoldingRegisters, before, span), options_.unit)});
    // And the other connection reads the overlapping range too: every reader must see it.
    out.steps.push_back(
        Step{Op::Send, static_cast<std::uint8_t>(1 - reader), 0, 0,
             frame(pdu5(coils ? kReadCoils : kReadHoldingRegisters, before, span), options_.unit)});
    // Registers have a second reader, FC 17: its read part must show the same values (its own
    // write goes to a register of the state range outside the window, so it changes nothing
    // there).
    if (!coils && span <= lim::kMaxRwReadRegisters) {
        const std::uint32_t last = std::min<std::uint32_t>(
            0xFFFFu, std::uint32_t{options_.state.base} + options_.state.span - 1);
        const std::uint32_t scratch =
            last >= std::uint32_t{before} + span ? last : std::uint32_t{options_.state.base};
        if (scratch < before || scratch >= std::uint32_t{before} + span) {
            const std::vector<std::uint8_t> value = register_bytes({word()});
            codec::Request rw;
            rw.function = kReadWriteMultipleRegisters;
            rw.address = before;
            rw.quantity = span;
            rw.write_address = static_cast<std::uint16_t>(scratch);
            rw.write_quantity = 1;
            rw.payload = value;
            out.steps.push_back(Step{Op::Send, static_cast<std::uint8_t>(1 - reader), 0, 0,
                                     frame(encode_pdu(rw), options_.unit)});
        }
    }
}

}  // namespace mbstorm::netfuzz
