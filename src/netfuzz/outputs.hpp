// Results of a fuzz campaign: for CI a JSON summary, JUnit XML (one test case per mutation
// class, a failure per finding) and SARIF 2.1.0 (one result per finding); for people a
// self-contained HTML page.
#pragma once

#include <string>

#include "netfuzz/campaign.hpp"

namespace mbstorm::netfuzz {

struct RunInfo {
    std::string target;
    std::uint64_t seed = 0;
    bool naive = false;
};

std::string format_fuzz_json(const CampaignResult& r, const RunInfo& info);
std::string format_fuzz_junit(const CampaignResult& r, const RunInfo& info);
std::string format_fuzz_sarif(const CampaignResult& r, const RunInfo& info);
// One self-contained HTML page: the run, the device model, the findings and, in coverage
// mode, edges over time (a chart) and by function code.
std::string format_fuzz_html(const CampaignResult& r, const RunInfo& info);
// The console's final summary (several lines).
std::string format_fuzz_summary(const CampaignResult& r, const RunInfo& info);

}  // namespace mbstorm::netfuzz
