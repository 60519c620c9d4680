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
