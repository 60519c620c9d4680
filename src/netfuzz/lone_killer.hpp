// The confirm stage's first question about a crash from a case of several requests on one
// connection: which request kills the target alone. A server that writes its answers in one go
// after reading everything it has dies before answering the requests ahead of the one that
// killed it, so the first request left unanswered names the wrong handler (a crash on a write
// filed under the read before it). Each request runs alone, in order, until one kills the
// target; the crash is then keyed by that request.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "netfuzz/case.hpp"
#include "netfuzz/executor.hpp"
#include "netfuzz/oracle.hpp"

namespace mbstorm::netfuzz {

// A case sending one request, framed as the target speaks.
Case one_request_case(const std::vector<std::uint8_t>& pdu, std::uint8_t unit, MutationClass cls,
                      std::uint16_t tid, codec::Framing framing);

// What looking for the lone killer needs of the campaign.
class LoneRuns {
  public:
    virtual ~LoneRuns() = default;
    virtual bool can_afford(unsigned runs) const = 0;
    // Runs a case alone, counted as an isolated run.
    virtual Execution run_request_alone(const Case& c) = 0;
    // After a run that left the target down: brought back, the restart charged to `cause`.
    // False when it stays down.
    virtual bool recover_from_death(const std::string& cause) = 0;
    // After a run that hung the whole server: false when it never comes back.
    virtual bool settle_hang() = 0;
};

struct LoneKiller {
    bool lost = false;  // the target did not come back: the campaign ends
    // The request that killed the target alone, as a case, and its run (its verdict the crash).
    std::optional<Case> request;
    Execution run;
};

// For a crash of `c` (one connection, more than one request, not a transport case), the request
// that kills the target alone, if one does within the budget. A case it does not apply to, or
// where no request does it alone (the crash needs them together), gives no request.
LoneKiller find_lone_killer(const Case& c, const TargetProfile& profile, LoneRuns& runs);

}  // namespace mbstorm::netfuzz
