// What a case's culprits are: the handlers (or transport classes) its frames meet, named as
// root-cause rules name them, so that a case carrying a culprit already known to crash or hang
// the target can be told before it is sent (campaign.cpp: skipped, or charged to that root
// cause when a batch dies).
#pragma once

#include <string>
#include <vector>

#include "codec/framing.hpp"
#include "netfuzz/case.hpp"
#include "netfuzz/oracle.hpp"
#include "netfuzz/wire.hpp"

namespace mbstorm::netfuzz {

// The culprit part of a rule that names one ("no-answer/fc07-valid" -> "fc07-valid").
std::string culprit_of(const std::string& rule);

// The frames a case sends on its first connection, put back together: for a transport case
// (split, drip, ...) the requests it delivers in the end. False when the bytes are not a clean
// run of complete frames or the case uses other steps.
bool reassemble(const Case& c, Case& plain, codec::Framing framing);

// Calls `visit` with each whole frame the case sends, described, until it returns false.
template <class Visit>
void for_each_request(const Case& c, const TargetProfile& profile, Visit&& visit) {
    for (const Step& s : c.steps) {
        if (s.op != Op::Send) continue;
        std::size_t consumed = 0;
        for (const std::vector<std::uint8_t>& view :
             request_views(s.bytes, profile.framing, consumed)) {
            RequestInfo info;
            describe_request(view, profile, info);
            if (!visit(info)) return;
        }
    }
}

// A culprit as signatures name it: a handler's with the kind of request ("fc10/invalid").
std::string signature_of(std::string culprit, const RequestInfo& info);

// What a case's culprits would be, each with whether its request is valid: "fc10/valid",
// "fc10/invalid". A crash on a handler's invalid requests says nothing of its valid ones (and
// the other way round), so only requests of the same kind are skipped once it is known. A
// frame with a non-zero protocol id is named by its class and by the handler it reaches on a
// target that ignores the protocol id.
std::vector<std::string> signatures(const Case& c, const TargetProfile& profile);

// Whether any frame the case delivers has a PDU of the wrong length for its function code.
bool carries_length_mismatch(const Case& c, const TargetProfile& profile);

}  // namespace mbstorm::netfuzz
