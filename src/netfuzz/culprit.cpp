#include "netfuzz/culprit.hpp"

#include <fmt/format.h>

#include "codec/limits.hpp"
#include "netfuzz/rules.hpp"

namespace mbstorm::netfuzz {

namespace lim = codec::limits;

std::string culprit_of(const std::string& rule) {
    const auto slash = rule.find('/');
    return slash == std::string::npos ? std::string() : rule.substr(slash + 1);
}

bool reassemble(const Case& c, Case& plain, codec::Framing framing) {
    std::vector<std::uint8_t> bytes;
    for (const Step& s : c.steps) {
        if (s.op == Op::Send && s.conn == 0)
            bytes.insert(bytes.end(), s.bytes.begin(), s.bytes.end());
        else if (s.op != Op::SideProbe && (s.op != Op::Await || s.conn != 0))
            return false;
    }
    std::size_t off = 0;
    const auto views = request_views(bytes, framing, off);
    if (off != bytes.size() || views.empty() || views[0].size() <= lim::kMbapHeader) return false;
    plain = Case{};
    plain.cls = views.size() > 1 ? MutationClass::Coalesced : MutationClass::ValidLimits;
    plain.function = views[0][lim::kMbapHeader];
    plain.number = c.number;
    plain.pipelinable = true;
    plain.steps.push_back(Step{Op::Send, 0, 0, 0, std::move(bytes)});
    return true;
}

std::string signature_of(std::string culprit, const RequestInfo& info) {
    if (culprit.rfind(kFunctionCulpritPrefix, 0) == 0)
        culprit += fmt::format("/{}", request_kind(info));
    return culprit;
}

std::vector<std::string> signatures(const Case& c, const TargetProfile& profile) {
    std::vector<std::string> out;
    if (is_transport_class(c.cls)) out.push_back(culprit_text(c.cls, nullptr));
    Case plain;
    const Case& framed =
        is_transport_class(c.cls) && reassemble(c, plain, profile.framing) ? plain : c;
    if (&framed == &c && is_transport_class(c.cls)) return out;
    for_each_request(framed, profile, [&](const RequestInfo& info) {
        out.push_back(signature_of(culprit_text(framed.cls, &info), info));
        // A target that ignores the protocol id hands the frame to its function's handler: a
        // crash or hang known there is met here too (else each such case kills it again).
        if (framed.cls == MutationClass::ProtocolId && !info.pdu.empty())
            out.push_back(signature_of(culprit_text(MutationClass::ValidLimits, &info), info));
        return true;
    });
    if (out.empty()) out.push_back(culprit_text(c.cls, nullptr));
    return out;
}

bool carries_length_mismatch(const Case& c, const TargetProfile& profile) {
    Case plain;
    const Case& framed =
        is_transport_class(c.cls) && reassemble(c, plain, profile.framing) ? plain : c;
    bool found = false;
    for_each_request(framed, profile, [&](const RequestInfo& info) {
        found = pdu_length_mismatch(info);
        return !found;
    });
    return found;
}

// How often a request of the wrong length is still sent once the target is known to lose the
// stream on one (for what else it may hit in the handler).
constexpr std::uint64_t kLengthMismatchShare = 16;

bool CostlyCases::would_retrigger(const Case& c) {
    if (length_mismatch_known_ && carries_length_mismatch(c, profile_))
        return ++length_mismatch_seen_ % kLengthMismatchShare != 0;
    if (culprits_.empty()) return false;
    // A stateful case is about its write: its read-backs (FC 03, 01, FC 17 over the window)
    // are valid requests that would otherwise be skipped once any crash on them is known.
    const bool stateful =
        c.cls == MutationClass::StatefulSame || c.cls == MutationClass::StatefulCross;
    const std::string about = fmt::format("fc{:02X}/", c.function);
    for (const std::string& k : signatures(c, profile_)) {
        if (stateful && k.rfind(about, 0) != 0) continue;
        if (culprits_.count(k) || culprits_.count(k.substr(0, k.find('/')))) return true;
    }
    return false;
}

void CostlyCases::learn(const std::string& culprit, const Case& c) {
    bool any = false;
    for (const std::string& k : signatures(c, profile_))
        if (k.rfind(culprit + "/", 0) == 0) {
            culprits_.insert(k);
            any = true;
        }
    if (!any) culprits_.insert(culprit);
}

}  // namespace mbstorm::netfuzz
