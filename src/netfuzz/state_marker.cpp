#include "netfuzz/state_marker.hpp"

#include <algorithm>

#include "codec/function_code.hpp"
#include "codec/mbap.hpp"
#include "netfuzz/ask.hpp"
#include "netfuzz/case.hpp"

namespace mbstorm::netfuzz {
namespace {

constexpr std::uint16_t kMarker = 0x4D42;  // "MB"

constexpr std::uint8_t kWriteRegister = codec::to_byte(codec::FunctionCode::WriteSingleRegister);
constexpr std::uint8_t kReadRegisters = codec::to_byte(codec::FunctionCode::ReadHoldingRegisters);

std::vector<std::uint8_t> pdu_of(std::uint8_t fc, std::uint16_t a, std::uint16_t b) {
    return {fc, static_cast<std::uint8_t>(a >> 8), static_cast<std::uint8_t>(a),
            static_cast<std::uint8_t>(b >> 8), static_cast<std::uint8_t>(b)};
}

}  // namespace

bool may_write_register(codec::Bytes pdu, std::uint16_t address) noexcept {
    if (pdu.empty()) return false;
    const codec::FunctionInfo* info = codec::function_info(pdu[0]);
    if (!info || !info->writes || info->table != codec::Table::HoldingRegisters) return false;
    const codec::AddressFields fields = codec::address_fields(info->request);
    // FC 17 writes its second range; the quantity follows a range's start where there is one.
    const std::size_t at = fields.second ? fields.second : fields.first;
    if (at == 0 || pdu.size() < at + 2) return false;
    const std::uint32_t start = codec::load_be16(pdu.data() + at);
    const bool has_quantity = fields.second || info->quantity.max > 0;
    std::uint32_t count = 1;
    if (has_quantity) count = pdu.size() >= at + 4 ? codec::load_be16(pdu.data() + at + 2) : 0xFFFF;
    return address >= start && address < start + std::max<std::uint32_t>(count, 1);
}

bool StateMarker::arm(const DeviceModel& model) {
    const TableModel& holding = model.table(codec::Table::HoldingRegisters);
    if (holding.ranges.empty() || holding.writes != WritesStick::Yes) return false;
    const auto largest = std::max_element(
        holding.ranges.begin(), holding.ranges.end(),
        [](const AddressRange& a, const AddressRange& b) { return a.size() < b.size(); });
    // The middle: the map's edges are where the fuzzer's own writes go most.
    return arm_at(static_cast<std::uint16_t>(largest->first + (largest->size() - 1) / 2));
}

bool StateMarker::arm_at(std::uint16_t address) {
    address_ = address;
    if (!read_register(initial_)) return false;
    value_ = initial_ == kMarker ? static_cast<std::uint16_t>(~kMarker) : kMarker;
    return rearm();
}

bool StateMarker::rearm() {
    std::uint16_t seen = 0;
    armed_ = write(value_) && read_register(seen) && seen == value_;
    return armed_;
}

StateMarker::Reading StateMarker::read(std::uint16_t& seen) {
    if (!read_register(seen)) return Reading::Unreadable;
    if (seen == value_) return Reading::Kept;
    armed_ = false;
    return Reading::Reset;
}

bool StateMarker::write(std::uint16_t v) {
    bool connected = false;
    const auto answers = ask_pipelined(
        target_,
        {frame_pdu(pdu_of(kWriteRegister, address_, v), 0, profile_.unit, profile_.framing)},
        timeout_ms_, connected);
    return !answers.empty() && !answers.front().empty() && answers.front()[0] == kWriteRegister;
}

bool StateMarker::read_register(std::uint16_t& out) {
    bool connected = false;
    const auto answers = ask_pipelined(
        target_,
        {frame_pdu(pdu_of(kReadRegisters, address_, 1), 0, profile_.unit, profile_.framing)},
        timeout_ms_, connected);
    if (answers.empty()) return false;
    const std::vector<std::uint8_t>& a = answers.front();
    if (a.size() != 4 || a[0] != kReadRegisters || a[1] != 2) return false;
    out = codec::load_be16(a.data() + 2);
    return true;
}

}  // namespace mbstorm::netfuzz
