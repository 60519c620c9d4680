#include "netfuzz/rationing.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "codec/function_code.hpp"
#include "netfuzz/culprit.hpp"
#include "netfuzz/field_repair.hpp"

namespace mbstorm::netfuzz {
namespace {

// The share of the run a target that pauses after exceptions may spend in those pauses, and
// how often a request owed such an exception whose kind was sent already goes out.
constexpr double kPauseShare = 0.25;
constexpr std::uint64_t kSameKindShare = 32;
// How often a request to a unit id the device does not answer goes out.
constexpr std::uint64_t kSilentUnitShare = 16;

// What a request owed an exception is, for rationing: its function, why the codec refuses it,
// and which fields are wrong (its address outside the map is a kind of its own).
std::string pausing_kind(const RequestInfo& info, const DeviceModel& m) {
    std::string kind = fmt::format("{:02x}/{}", info.pdu.empty() ? 0 : info.pdu[0],
                                   codec::error_name(info.status.error));
    for (const RequestField f : wrong_fields(info.pdu, m))
        kind += fmt::format("/{}", field_name(f));
    return kind;
}

}  // namespace

bool Rationing::to_silent_unit(const Case& c, const TargetProfile& profile, const DeviceModel& m) {
    if (m.units.empty() || m.units.size() == 256) return false;
    bool silent = false;
    for_each_request(c, profile, [&](const RequestInfo& info) {
        silent = std::find(m.units.begin(), m.units.end(), info.header.unit_id) == m.units.end();
        return !silent;
    });
    return silent;
}

bool Rationing::holds_back(const Case& c, const TargetProfile& profile, const DeviceModel& m,
                           double elapsed_s) {
    if (to_silent_unit(c, profile, m) && ++silent_units_seen_ % kSilentUnitShare != 0) return true;
    if (!m.pauses_after_exceptions()) return false;
    unsigned pause_ms = 0;
    std::string kind;
    for_each_request(c, profile, [&](const RequestInfo& info) {
        const std::uint8_t fc = info.pdu.empty() ? 0 : info.pdu[0];
        std::size_t code = static_cast<std::size_t>(info.status.exception);
        if (profile.unsupported[fc]) code = 1;
        if (!owes_exception(info, profile) || code >= m.exception_pause_ms.size() ||
            m.exception_pause_ms[code] == 0)
            return true;
        pause_ms = m.exception_pause_ms[code];
        kind = pausing_kind(info, m);
        return false;
    });
    if (pause_ms == 0) return false;
    // A kind not sent yet goes out while the pauses stay within their share of the run; the
    // rest, one in kSameKindShare, and only within that share too.
    const bool affordable = static_cast<double>(pause_spent_ms_) <= kPauseShare * elapsed_s * 1e3;
    const bool novel = !paused_kinds_.count(kind);
    if (!affordable || (!novel && ++same_kind_seen_ % kSameKindShare != 0)) return true;
    paused_kinds_.insert(kind);
    pause_spent_ms_ += pause_ms;
    return false;
}

}  // namespace mbstorm::netfuzz
