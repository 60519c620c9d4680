#include "netfuzz/lone_killer.hpp"

#include "netfuzz/culprit.hpp"
#include "netfuzz/finding.hpp"
#include "netfuzz/target_care.hpp"

namespace mbstorm::netfuzz {

Case one_request_case(const std::vector<std::uint8_t>& pdu, std::uint8_t unit, MutationClass cls,
                      std::uint16_t tid, codec::Framing framing) {
    Case c;
    c.cls = cls;
    c.function = pdu.empty() ? 0 : pdu[0];
    c.steps.push_back(Step{Op::Send, 0, 0, 0, frame_pdu(pdu, tid, unit, framing)});
    return c;
}

LoneKiller find_lone_killer(const Case& c, const TargetProfile& profile, LoneRuns& runs) {
    LoneKiller out;
    if (is_transport_class(c.cls) || c.connections() > 1) return out;
    std::vector<Case> alone;
    for_each_request(c, profile, [&](const RequestInfo& info) {
        alone.push_back(one_request_case({info.pdu.begin(), info.pdu.end()}, info.header.unit_id,
                                         c.cls, 0x0D00, profile.framing));
        return true;
    });
    if (alone.size() < 2) return out;
    for (Case& one : alone) {
        if (!runs.can_afford(1)) return out;
        Execution e = runs.run_request_alone(one);
        if (!e.target_down) {
            if (whole_server_hang(e.verdict) && !runs.settle_hang()) out.lost = true;
            if (out.lost) return out;
            continue;
        }
        out.lost = !runs.recover_from_death(e.verdict ? root_cause_key(e.verdict) : "");
        if (!out.lost) {
            out.request = std::move(one);
            out.run = std::move(e);
        }
        return out;
    }
    return out;
}

}  // namespace mbstorm::netfuzz
