#include "netfuzz/rationing.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <tuple>

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
// The group of every function code the device or the codec does not support.
constexpr unsigned kUnsupportedGroup = 256;

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

bool Rationing::affordable(double elapsed_s) const noexcept {
    return static_cast<double>(pause_spent_ms_) <= kPauseShare * elapsed_s * 1e3;
}

void Rationing::send(const Kind& k) {
    if (paused_kinds_.insert(k.name).second) ++sent_by_group_[k.group];
    waiting_.erase(k.name);
    pause_spent_ms_ += k.pause_ms;
    round_charge_ms_ += k.pause_ms;
}

void Rationing::round_took(double ms) noexcept {
    // A round cannot have paused longer than it took: the target answered some of those
    // requests without the exception (or the pause) the model predicted.
    if (ms < static_cast<double>(round_charge_ms_))
        pause_spent_ms_ -= round_charge_ms_ - static_cast<std::uint64_t>(ms);
    round_charge_ms_ = 0;
}

bool Rationing::holds_back(const Case& c, const TargetProfile& profile, const DeviceModel& m,
                           double elapsed_s) {
    if (to_silent_unit(c, profile, m) && ++silent_units_seen_ % kSilentUnitShare != 0) return true;
    if (!m.pauses_after_exceptions()) return false;
    Kind kind;
    for_each_request(c, profile, [&](const RequestInfo& info) {
        const std::uint8_t fc = info.pdu.empty() ? 0 : info.pdu[0];
        const bool unsupported =
            profile.unsupported[fc] || info.status.error == codec::CodecError::UnsupportedFunction;
        const std::size_t code = unsupported ? 1 : static_cast<std::size_t>(info.status.exception);
        if (!owes_exception(info, profile) || code >= m.exception_pause_ms.size() ||
            m.exception_pause_ms[code] == 0)
            return true;
        kind.pause_ms = m.exception_pause_ms[code];
        kind.group = unsupported ? kUnsupportedGroup : fc;
        kind.name = fmt::format("{:02x}/{}", fc, codec::error_name(info.status.error));
        kind.length_mismatch = info.status.error == codec::CodecError::Truncated ||
                               info.status.error == codec::CodecError::TrailingBytes;
        if (kind.length_mismatch) return false;  // its fields are not where they seem
        for (const RequestField f : wrong_fields(info.pdu, m)) {
            const int side = wrong_count_side(info.pdu, f, m);
            kind.name += fmt::format("/{}{}", field_name(f), side > 0 ? "+" : side < 0 ? "-" : "");
            ++kind.wrong;
        }
        return false;
    });
    if (kind.pause_ms == 0) return false;
    if (!paused_kinds_.count(kind.name)) {
        // Sent by release(), in rank among the others waiting.
        waiting_.try_emplace(kind.name, Waiting{kind, c, ++waited_});
        return true;
    }
    // A kind sent already: one in kSameKindShare, after every waiting kind.
    if (!affordable(elapsed_s) || !waiting_.empty() || ++same_kind_seen_ % kSameKindShare != 0)
        return true;
    send(kind);
    return false;
}

std::vector<Case> Rationing::release(double elapsed_s) {
    std::vector<Case> out;
    while (!waiting_.empty() && affordable(elapsed_s)) {
        // A length that disagrees with the fields tries the framing a device mostly shares
        // across its function codes: such a kind goes a round after its code's field kinds.
        const auto rank = [&](const Waiting& w) {
            return std::make_tuple(sent_by_group_[w.kind.group] + (w.kind.length_mismatch ? 1 : 0),
                                   w.kind.wrong, w.order);
        };
        auto best = waiting_.begin();
        for (auto it = waiting_.begin(); it != waiting_.end(); ++it)
            if (rank(it->second) < rank(best->second)) best = it;
        out.push_back(std::move(best->second.first));
        send(Kind(best->second.kind));  // a copy: send() erases the entry it names
    }
    return out;
}

}  // namespace mbstorm::netfuzz
