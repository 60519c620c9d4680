// What a case's culprits are: the handlers (or transport classes) its frames meet, named as
// root-cause rules name them, so that a case carrying a culprit already known to crash or hang
// the target can be told before it is sent (campaign.cpp: skipped, or charged to that root
// cause when a batch dies).
#pragma once

#include <cstdint>
#include <set>
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

// The cases not worth sending again: those that carry a culprit of a known crash or hang
// (each would cost a restart or a timeout to show what is known), and, once the target is known
// to lose the stream on a request of the wrong length, all but one in 16 of those.
class CostlyCases {
  public:
    explicit CostlyCases(const TargetProfile& profile) : profile_(profile) {}
    bool would_retrigger(const Case& c);
    // The requests of `c` whose culprit is `culprit`, by signature (the culprit alone when it
    // has none: a transport class, a request not framed).
    void learn(const std::string& culprit, const Case& c);
    // Every request of a handler (crashed by more than one kind of request).
    void learn_handler(const std::string& culprit) { culprits_.insert(culprit); }
    void length_mismatch_loses_the_stream() noexcept { length_mismatch_known_ = true; }

  private:
    const TargetProfile& profile_;
    std::set<std::string> culprits_;  // signatures and culprits of known crashes and hangs
    bool length_mismatch_known_ = false;
    std::uint64_t length_mismatch_seen_ = 0;
};

}  // namespace mbstorm::netfuzz
