#include "netfuzz/field_repair.hpp"

#include "codec/function_code.hpp"
#include "codec/mbap.hpp"

namespace mbstorm::netfuzz {

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

}  // namespace mbstorm::netfuzz
