#include "netfuzz/field_repair.hpp"

#include <algorithm>

#include "codec/function_code.hpp"
#include "codec/limits.hpp"
#include "codec/mbap.hpp"
#include "codec/pdu.hpp"
#include "netfuzz/generator.hpp"
#include "netfuzz/wire.hpp"

namespace mbstorm::netfuzz {
namespace {

namespace lim = codec::limits;

// Whether `count` items from `start` lie in one range of `t` (a single item when count is 0).
bool fits_one_range(const TableModel& t, std::uint16_t start, std::uint16_t count) {
    const AddressRange* r = t.range_of(start);
    return r && std::uint32_t{start} + std::max<std::uint32_t>(count, 1) - 1 <= r->last;
}

bool inside_map(const codec::Request& q, const DeviceModel& model) {
    const auto table = codec::function_table(q.function);
    if (!table) return true;
    const TableModel& t = model.table(*table);
    if (!fits_one_range(t, q.address, q.quantity)) return false;
    return !codec::request_is(q.function, codec::RequestShape::ReadWriteRegisters) ||
           fits_one_range(t, q.write_address, q.write_quantity);
}

constexpr RequestField kFields[] = {
    RequestField::Quantity,     RequestField::WriteQuantity, RequestField::ByteCount,
    RequestField::DataLength,   RequestField::Value,         RequestField::Address,
    RequestField::WriteAddress,
};

std::optional<std::uint16_t> word_at(codec::Bytes pdu, std::size_t at) {
    if (at == 0 || pdu.size() < at + 2) return std::nullopt;
    return codec::load_be16(pdu.data() + at);
}

void store_word(std::vector<std::uint8_t>& pdu, std::size_t at, std::uint16_t v) {
    codec::store_be16(pdu.data() + at, v);
}

bool within(lim::QuantityRange r, std::uint16_t n) {
    return n >= r.min && n <= r.max;
}

// An address field, where its count lies and the limits that count must keep.
struct RangeField {
    std::size_t address = 0, count = 0;
    lim::QuantityRange limits;
};

std::optional<RangeField> range_field(std::uint8_t fc, RequestField field) {
    const codec::FunctionInfo* info = codec::function_info(fc);
    if (!info) return std::nullopt;
    const codec::AddressFields at = codec::address_fields(info->request);
    const codec::RequestFields rf = codec::request_fields(fc);
    if (field == RequestField::Address && at.first)
        return RangeField{at.first, rf.quantity, rf.quantity_range};
    if (field == RequestField::WriteAddress && at.second)
        return RangeField{at.second, rf.written, rf.written_range};
    return std::nullopt;
}

// The count a range is judged with: its own when valid, else one item (a wrong count is the
// count's fault, not the address's).
std::uint16_t judged_count(codec::Bytes pdu, const RangeField& r) {
    const auto n = word_at(pdu, r.count);
    return n && within(r.limits, *n) ? *n : 1;
}

const TableModel* known_table(std::uint8_t fc, const DeviceModel& model) {
    const auto table = codec::function_table(fc);
    if (!table || model.table(*table).ranges.empty()) return nullptr;
    return &model.table(*table);
}

bool range_outside_map(codec::Bytes pdu, RequestField field, const DeviceModel& model) {
    const auto r = range_field(pdu[0], field);
    const TableModel* t = known_table(pdu[0], model);
    const auto start = r ? word_at(pdu, r->address) : std::nullopt;
    return t && start && !fits_one_range(*t, *start, judged_count(pdu, *r));
}

bool is_wrong(codec::Bytes pdu, RequestField field, const DeviceModel& model) {
    const codec::RequestFields rf = codec::request_fields(pdu[0]);
    const auto written = word_at(pdu, rf.written);
    const bool has_byte_count = rf.byte_count != 0 && pdu.size() > rf.byte_count;
    switch (field) {
        case RequestField::Quantity: {
            const auto n = word_at(pdu, rf.quantity);
            return n && !within(rf.quantity_range, *n);
        }
        case RequestField::WriteQuantity:
            return rf.written != rf.quantity && written && !within(rf.written_range, *written);
        case RequestField::ByteCount:
            return has_byte_count && written && pdu[rf.byte_count] != rf.data_bytes(*written);
        case RequestField::DataLength:
            return has_byte_count && pdu.size() - rf.data != pdu[rf.byte_count];
        case RequestField::Value: {
            const auto v = word_at(pdu, rf.coil_value);
            return v && *v != lim::kCoilOn && *v != lim::kCoilOff;
        }
        case RequestField::Address:
        case RequestField::WriteAddress:
            return range_outside_map(pdu, field, model);
    }
    return false;
}

// A count made valid: the one its byte count announces where that is valid, else the least.
std::uint16_t repaired_count(codec::Bytes pdu, const codec::RequestFields& rf, std::size_t at,
                             lim::QuantityRange limits) {
    if (at == rf.written && rf.byte_count != 0 && pdu.size() > rf.byte_count) {
        const unsigned bytes = pdu[rf.byte_count];
        const unsigned n = rf.packed_bits ? bytes * 8u : bytes / 2u;
        if (n <= limits.max && n >= limits.min &&
            rf.data_bytes(static_cast<std::uint16_t>(n)) == bytes)
            return static_cast<std::uint16_t>(n);
    }
    return limits.min;
}

// The first range of the table that holds `count` items (the first one when none does).
std::uint16_t start_in_map(const TableModel& t, std::uint16_t count) {
    for (const AddressRange& r : t.ranges)
        if (std::uint32_t{r.last} - r.first + 1 >= count) return r.first;
    return t.ranges.front().first;
}

void repair(std::vector<std::uint8_t>& pdu, RequestField field, const DeviceModel& model) {
    const codec::RequestFields rf = codec::request_fields(pdu[0]);
    switch (field) {
        case RequestField::Quantity:
            store_word(pdu, rf.quantity, repaired_count(pdu, rf, rf.quantity, rf.quantity_range));
            return;
        case RequestField::WriteQuantity:
            store_word(pdu, rf.written, repaired_count(pdu, rf, rf.written, rf.written_range));
            return;
        case RequestField::ByteCount: {
            // Data that agreed with the wrong byte count moves with it: else the repair would
            // make another field wrong.
            const std::size_t bytes = rf.data_bytes(codec::load_be16(pdu.data() + rf.written));
            const bool data_agreed = pdu.size() - rf.data == pdu[rf.byte_count];
            if (bytes > 0xFF || rf.data + bytes > lim::kMaxPdu) return;
            pdu[rf.byte_count] = static_cast<std::uint8_t>(bytes);
            if (data_agreed) pdu.resize(rf.data + bytes);
            return;
        }
        case RequestField::DataLength:
            if (rf.data + pdu[rf.byte_count] <= lim::kMaxPdu)
                pdu.resize(rf.data + pdu[rf.byte_count]);
            return;
        case RequestField::Value:
            store_word(pdu, rf.coil_value, lim::kCoilOn);
            return;
        case RequestField::Address:
        case RequestField::WriteAddress: {
            const RangeField r = *range_field(pdu[0], field);
            store_word(pdu, r.address,
                       start_in_map(*known_table(pdu[0], model), judged_count(pdu, r)));
            return;
        }
    }
}

}  // namespace

std::optional<std::vector<std::uint8_t>> with_addresses_in_map(codec::Bytes pdu,
                                                               const DeviceModel& model) {
    if (pdu.empty()) return std::nullopt;
    const codec::FunctionInfo* info = codec::function_info(pdu[0]);
    const auto table = codec::function_table(pdu[0]);
    if (!info || !table) return std::nullopt;
    const TableModel& t = model.table(*table);
    if (t.ranges.empty()) return std::nullopt;
    const std::uint16_t inside = t.ranges.front().first;
    std::vector<std::uint8_t> out(pdu.begin(), pdu.end());
    bool moved = false;
    const codec::AddressFields fields = codec::address_fields(info->request);
    for (const std::size_t at : {fields.first, fields.second}) {
        if (at == 0 || out.size() < at + 2) continue;
        if (t.contains(codec::load_be16(out.data() + at))) continue;
        out[at] = static_cast<std::uint8_t>(inside >> 8);
        out[at + 1] = static_cast<std::uint8_t>(inside);
        moved = true;
    }
    if (!moved) return std::nullopt;
    return out;
}

std::optional<std::vector<std::uint8_t>> valid_request_in_map(std::uint8_t fc,
                                                              const DeviceModel& model) {
    // The generator's structured requests hold valid ones of every public code; the first of
    // this code that is valid once its addresses are in the map is the one.
    for (std::vector<std::uint8_t> pdu : structured_pdus()) {
        if (pdu.empty() || pdu[0] != fc) continue;
        if (auto moved = with_addresses_in_map(pdu, model)) pdu = std::move(*moved);
        codec::Request q;
        if (!codec::decode_request(pdu, q).ok()) continue;
        if (model.empty() || inside_map(q, model)) return pdu;
    }
    return std::nullopt;
}

std::string_view field_name(RequestField field) noexcept {
    switch (field) {
        case RequestField::Quantity:
            return "quantity";
        case RequestField::WriteQuantity:
            return "write-quantity";
        case RequestField::ByteCount:
            return "byte-count";
        case RequestField::DataLength:
            return "data-length";
        case RequestField::Value:
            return "value";
        case RequestField::Address:
            return "address";
        case RequestField::WriteAddress:
            return "write-address";
    }
    return "field";
}

std::vector<RequestField> wrong_fields(codec::Bytes pdu, const DeviceModel& model) {
    std::vector<RequestField> out;
    if (pdu.empty() || !codec::function_info(pdu[0])) return out;
    for (const RequestField f : kFields)
        if (is_wrong(pdu, f, model)) out.push_back(f);
    return out;
}

int wrong_count_side(codec::Bytes pdu, RequestField field, const DeviceModel& model) {
    if (pdu.empty() || !codec::function_info(pdu[0]) || !is_wrong(pdu, field, model)) return 0;
    const codec::RequestFields rf = codec::request_fields(pdu[0]);
    const auto side = [](bool over) { return over ? 1 : -1; };
    switch (field) {
        case RequestField::Quantity:
            return side(*word_at(pdu, rf.quantity) > rf.quantity_range.max);
        case RequestField::WriteQuantity:
            return side(*word_at(pdu, rf.written) > rf.written_range.max);
        case RequestField::ByteCount:
            return side(pdu[rf.byte_count] > rf.data_bytes(*word_at(pdu, rf.written)));
        case RequestField::DataLength:
            return side(pdu.size() - rf.data > pdu[rf.byte_count]);
        case RequestField::Value:
        case RequestField::Address:
        case RequestField::WriteAddress:
            return 0;
    }
    return 0;
}

std::optional<std::vector<std::uint8_t>> with_field_repaired(codec::Bytes pdu, RequestField field,
                                                             const DeviceModel& model) {
    if (pdu.empty() || !codec::function_info(pdu[0]) || !is_wrong(pdu, field, model))
        return std::nullopt;
    std::vector<std::uint8_t> out(pdu.begin(), pdu.end());
    repair(out, field, model);
    if (is_wrong(out, field, model)) return std::nullopt;
    return out;
}

std::optional<std::vector<std::uint8_t>> step_request(const Step& s, int fc,
                                                      codec::Framing framing) {
    if (s.op != Op::Send) return std::nullopt;
    std::vector<std::uint8_t> mbap;
    if (framing == codec::Framing::Mbap) {
        if (s.bytes.size() <= lim::kMbapHeader ||
            codec::announced_adu_size(s.bytes.data()) != s.bytes.size())
            return std::nullopt;
        mbap = s.bytes;
    } else {
        WireFrame wf;
        if (cut_frame(s.bytes, framing, true, 0, wf) != WireCut::Frame ||
            wf.size != s.bytes.size() || !wf.discard.empty())
            return std::nullopt;
        mbap = std::move(wf.mbap);
    }
    if (mbap.size() <= lim::kMbapHeader || mbap[lim::kMbapHeader] != fc) return std::nullopt;
    return mbap;
}

void set_step_request(Step& s, const std::vector<std::uint8_t>& mbap, codec::Framing framing) {
    s.bytes = framing == codec::Framing::Mbap ? mbap : reframe(mbap, framing);
}

std::vector<std::uint8_t> answered_bytes(const std::vector<TraceEvent>& trace) {
    std::vector<std::uint8_t> out;
    for (const TraceEvent& e : trace)
        if (e.kind == TraceKind::Recv && e.conn != kFreshConn)
            out.insert(out.end(), e.bytes.begin(), e.bytes.end());
    return out;
}

}  // namespace mbstorm::netfuzz
