// Cases aimed at the device's map (netfuzz/device_model.hpp): a request inside a valid range,
// valid but for at most one field, so that the code behind the target's address check runs
// (byte counts trusted once the address is good, a second range checked less carefully than
// the first); and every edge of every range, for every function code that takes an address.
#include <algorithm>

#include "codec/function_code.hpp"
#include "codec/limits.hpp"
#include "codec/mbap.hpp"
#include "netfuzz/generator.hpp"

namespace mbstorm::netfuzz {
namespace {

namespace lim = codec::limits;
using Pdu = std::vector<std::uint8_t>;
using codec::RequestShape;

// The most items one request of function `fc` may carry (v1.1b3, from the codec's table): the
// count its byte count follows (FC 0F, 10, FC 17's write part), else its quantity (01-04),
// else one item (05, 06, 16, 18).
std::uint32_t item_limit(std::uint8_t fc) {
    const codec::RequestFields rf = codec::request_fields(fc);
    if (rf.written) return rf.written_range.max;
    if (rf.quantity) return rf.quantity_range.max;
    return 1;
}

// A valid request of `fc` for `quantity` items at `address` (the write range of FC17 at
// `second`), values from `value`.
template <class Value>
Pdu request_at(std::uint8_t fc, std::uint16_t address, std::uint16_t quantity, std::uint16_t second,
               Value&& value) {
    const codec::FunctionInfo* info = codec::function_info(fc);
    codec::Request r;
    r.function = fc;
    r.address = address;
    r.quantity = quantity;
    std::vector<std::uint8_t> payload;
    std::vector<std::uint16_t> registers;
    switch (info->request) {
        case RequestShape::AddressQuantity:
        case RequestShape::FifoPointer:
            break;
        case RequestShape::SingleCoil:
            r.value = value() & 1 ? lim::kCoilOn : lim::kCoilOff;
            break;
        case RequestShape::SingleRegister:
            r.value = static_cast<std::uint16_t>(value());
            break;
        case RequestShape::MultipleCoils:
            for (int i = 0; i < (quantity + 7) / 8; ++i)
                payload.push_back(static_cast<std::uint8_t>(value()));
            break;
        case RequestShape::MultipleRegisters:
            for (int i = 0; i < quantity; ++i)
                registers.push_back(static_cast<std::uint16_t>(value()));
            payload = register_bytes(registers);
            break;
        case RequestShape::MaskWrite:
            r.and_mask = static_cast<std::uint16_t>(value());
            r.or_mask = static_cast<std::uint16_t>(value());
            break;
        case RequestShape::ReadWriteRegisters:
            r.write_address = second;
            r.write_quantity = quantity;
            for (int i = 0; i < quantity; ++i)
                registers.push_back(static_cast<std::uint16_t>(value()));
            payload = register_bytes(registers);
            break;
        case RequestShape::FunctionOnly:
        case RequestShape::SubFunction:
        case RequestShape::FileRecords:
        case RequestShape::MeiTransport:
            return Pdu{fc};  // no address: never asked for (see addressed())
    }
    r.payload = payload;
    return encode_pdu(r);
}

bool addressed(std::uint8_t fc) {
    const codec::FunctionInfo* info = codec::function_info(fc);
    return info && info->table && codec::address_fields(info->request).any();
}

// A write of many items whose quantity says one more or one fewer item (a byte more or fewer
// for coils: 8 items) than its byte count and data carry, the range still inside the block: a
// handler that checks the address, then trusts the byte count, runs past its buffer.
void disagree_on_quantity(Pdu& p, const codec::FunctionInfo& info, const AddressRange& r,
                          std::uint16_t at, std::uint32_t q) {
    const bool multi = info.request == RequestShape::MultipleCoils ||
                       info.request == RequestShape::MultipleRegisters;
    if (!multi || p.size() < 6) return;
    const std::uint32_t step = info.request == RequestShape::MultipleCoils ? 8 : 1;
    const bool room = std::uint32_t{at} + q + step <= std::uint32_t{r.last} + 1;
    const std::uint32_t wrong = room ? q + step : q > step ? q - step : q;
    codec::store_be16(p.data() + 3, static_cast<std::uint16_t>(wrong));
}

}  // namespace

bool Generator::pick_map_function(std::uint8_t& fc) {
    std::vector<std::uint8_t> usable;
    for (const codec::FunctionInfo& info : codec::public_functions()) {
        const std::uint8_t code = codec::to_byte(info.code);
        if (!addressed(code) || options_.unsupported[code]) continue;
        if (options_.model->table(*info.table).ranges.empty()) continue;
        usable.push_back(code);
    }
    if (usable.empty()) return false;
    fc = usable[rng_.below(static_cast<std::uint32_t>(usable.size()))];
    return true;
}

std::uint16_t Generator::model_address(bool coils, std::uint16_t room) {
    const TableModel& tm =
        options_.model->table(coils ? codec::Table::Coils : codec::Table::HoldingRegisters);
    if (tm.ranges.empty()) return state_address(room);
    const AddressRange& r = tm.ranges[rng_.below(static_cast<std::uint32_t>(tm.ranges.size()))];
    if (room == 0) return static_cast<std::uint16_t>(r.first + rng_.below(std::min(r.size(), 16u)));
    const std::uint32_t span = r.size() > room ? r.size() - room + 1 : 1;
    return static_cast<std::uint16_t>(r.first + rng_.below(span));
}

std::uint32_t Generator::map_room(bool coils, std::uint16_t address) const {
    const TableModel& tm =
        options_.model->table(coils ? codec::Table::Coils : codec::Table::HoldingRegisters);
    const AddressRange* r = tm.range_of(address);
    return r ? std::uint32_t{r->last} - address + 1 : 1;
}

void Generator::in_map(Case& out) {
    std::uint8_t fc = 0;
    if (!pick_map_function(fc)) return structured(out);
    const codec::FunctionInfo* info = codec::function_info(fc);
    const TableModel& tm = options_.model->table(*info->table);
    const AddressRange& r = tm.ranges[rng_.below(static_cast<std::uint32_t>(tm.ranges.size()))];
    const std::uint32_t spec_limit = item_limit(fc);
    const std::uint32_t limit = std::min(spec_limit, r.size());
    // Mostly few items: a small quantity is where off-by-ones live, and it fits anywhere.
    const std::uint32_t q =
        rng_.chance(2) ? 1 + rng_.below(std::min<std::uint32_t>(limit, 8)) : 1 + rng_.below(limit);
    const auto at = static_cast<std::uint16_t>(r.first + rng_.below(r.size() - q + 1));
    const std::uint16_t second = model_address(false, static_cast<std::uint16_t>(q));
    Pdu p = request_at(fc, at, static_cast<std::uint16_t>(q), second, [this] { return word(); });
    // One field made wrong in most cases (a pausing target gets fewer: see GeneratorOptions).
    const std::uint32_t odds = options_.model->pauses_after_exceptions() ? 4 : 3;
    if (rng_.below(odds) < 2 && p.size() >= 5) {
        const std::uint32_t end = at + q;  // one past the last item asked
        switch (rng_.below(7)) {
            case 0:  // quantity: 0, one more than allowed, or all ones
            {
                const std::uint16_t wrong[] = {0, static_cast<std::uint16_t>(spec_limit + 1),
                                               0xFFFF};
                codec::store_be16(p.data() + 3, rng_.pick(wrong));
            } break;
            case 1:  // the range runs one past the end of the block
                if (p.size() > 5 || info->request == RequestShape::AddressQuantity)
                    codec::store_be16(p.data() + 3,
                                      static_cast<std::uint16_t>(q + (r.last + 1u - end) + 1));
                break;
            case 2:  // the address one before the block or one past it
                codec::store_be16(p.data() + 1, static_cast<std::uint16_t>(
                                                    rng_.chance(2) ? r.first - 1u : r.last + 1u));
                break;
            case 3:  // byte count one off (writes of many items)
                if (p.size() > 6)
                    p[5] = static_cast<std::uint8_t>(p[5] + (rng_.chance(2) ? 1 : -1));
                break;
            case 6:  // the quantity disagrees with byte count and data, its range still inside
                disagree_on_quantity(p, *info, r, at, q);
                break;
            case 4:  // the data one byte short or long, the counts as they were
                if (rng_.chance(2))
                    p.pop_back();
                else if (p.size() < lim::kMaxPdu)
                    p.push_back(rng_.byte());
                break;
            default:  // FC17's second range past its block, the first valid; else a value
                if (info->request == RequestShape::ReadWriteRegisters)
                    codec::store_be16(p.data() + 5, static_cast<std::uint16_t>(
                                                        second + rng_.below(limit + 1) + 1));
                else if (p.size() >= 5)
                    codec::store_be16(p.data() + 3, word());
                break;
        }
    }
    out.cls = MutationClass::InMap;
    out.function = fc;
    out.pipelinable = true;
    out.steps.push_back(Step{Op::Send, 0, 0, 0, frame(p, options_.unit)});
}

void Generator::build_edges() {
    for (const codec::FunctionInfo& info : codec::public_functions()) {
        const std::uint8_t fc = codec::to_byte(info.code);
        if (!addressed(fc) || options_.unsupported[fc]) continue;
        const TableModel& tm = options_.model->table(*info.table);
        const std::uint32_t limit = item_limit(fc);
        const bool ranged = limit > 1;
        for (std::size_t k = 0; k < tm.ranges.size(); ++k) {
            const AddressRange& r = tm.ranges[k];
            const auto q = std::min(limit, r.size());
            const std::uint32_t last_start = r.last - q + 1;
            // First, last, one before, one past (one item); the block to its last item and one
            // item further.
            std::vector<std::pair<std::uint32_t, std::uint32_t>> at = {
                {r.first, 1}, {r.last, 1}, {r.first - 1u, 1}, {r.last + 1u, 1}};
            if (ranged) {
                at.emplace_back(last_start, q);
                at.emplace_back(last_start + 1, q);
            }
            // From this block's last item across the hole to the next block's first.
            if (ranged && k + 1 < tm.ranges.size() && tm.ranges[k + 1].first - r.last + 1u <= limit)
                at.emplace_back(r.last, tm.ranges[k + 1].first - r.last + 1u);
            for (const auto& [a, n] : at) {
                if (a > 0xFFFF) continue;
                edges_.push_back(
                    Edge{fc, static_cast<std::uint16_t>(a), static_cast<std::uint16_t>(n), false});
                // FC17: the write range at the same edge, its read range valid.
                if (info.request == RequestShape::ReadWriteRegisters)
                    edges_.push_back(Edge{fc, static_cast<std::uint16_t>(a),
                                          static_cast<std::uint16_t>(n), true});
            }
        }
    }
}

void Generator::map_edge(Case& out) {
    if (edges_.empty()) build_edges();
    if (edges_.empty()) return in_map(out);
    const Edge e = edges_[edge_cursor_++ % edges_.size()];
    // Values drawn afresh at each visit: a device may misbehave at one edge for one value.
    auto value = [this] { return word(); };
    const std::uint16_t inside = model_address(false, e.quantity);
    const Pdu p = e.second_range ? request_at(e.function, inside, e.quantity, e.address, value)
                                 : request_at(e.function, e.address, e.quantity, inside, value);
    out.cls = MutationClass::MapEdge;
    out.function = p[0];
    out.pipelinable = true;
    out.steps.push_back(Step{Op::Send, 0, 0, 0, frame(p, options_.unit)});
}

}  // namespace mbstorm::netfuzz
