// --baseline FILE: the root causes an earlier run reported (its --json summary or its SARIF
// file). Findings whose root cause is in it are reported as known and do not fail the run, so
// that a CI job fails on what is new, not on a defect the team has already filed.
#pragma once

#include <set>
#include <string>
#include <vector>

#include "netfuzz/campaign.hpp"
#include "util/error.hpp"

namespace mbstorm::netfuzz {

struct Baseline {
    std::string file;
    std::set<std::string> keys;  // root-cause keys ("crash:target-down/fc0F")
};

// Reads `path`: an object with "findings" (fuzz --json; each finding's "root_cause") or a
// SARIF log (each result's partialFingerprints.mbstormKey). An Error naming the file and what
// is wrong (NotFound when there is no such file).
Result<Baseline> load_baseline(const std::string& path);

// Marks each finding known or new and records the baseline's keys no finding had.
void apply_baseline(const Baseline& b, CampaignResult& r);

}  // namespace mbstorm::netfuzz
