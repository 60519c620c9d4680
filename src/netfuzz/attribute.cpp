#include "netfuzz/attribute.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "netfuzz/rules.hpp"

namespace mbstorm::netfuzz {

std::vector<std::string> lane_break_keys(const LaneBreak& b, LengthMismatchClose how) {
    std::vector<std::string> keys;
    const std::string close = b.closed ? "unexpected-close:" : "hang:";
    if (b.length_mismatch)
        keys.push_back(how == LengthMismatchClose::RefusesTheFrame && b.closed
                           ? fmt::format("unexpected-close:{}", kClosesOnInvalidRequestRule)
                           : fmt::format("stream:{}", kStreamLostRule));
    if (b.closed && b.unanswered_invalid)  // the executor's order (executor.cpp)
        keys.push_back(fmt::format("unexpected-close:{}", kClosesOnInvalidRequestRule));
    if (b.has_previous && b.previous_exception)
        keys.push_back(close + after_exception_rule(b.closed));
    if (b.has_previous) keys.push_back(close + after_request_rule(b.closed, b.previous_culprit));
    keys.push_back(close + unanswered_rule(b.closed, b.unanswered_culprit));
    return keys;
}

std::vector<std::size_t> triage(const BatchResult& br, LengthMismatchClose how,
                                const KnownVerdict& known_verdict, const KnownKey& known_key) {
    std::vector<std::size_t> suspects = br.suspects;
    for (const auto& [ci, v] : br.verdicts)
        if (!known_verdict(v, ci)) suspects.push_back(ci);
    for (const LaneBreak& b : br.breaks) {
        const std::size_t ci = b.has_previous ? b.previous_case : b.unanswered_case;
        for (const std::string& k : lane_break_keys(b, how)) {
            if (!known_key(k, ci)) continue;
            std::erase(suspects, b.previous_case);
            std::erase(suspects, b.unanswered_case);
            break;
        }
    }
    std::sort(suspects.begin(), suspects.end());
    suspects.erase(std::unique(suspects.begin(), suspects.end()), suspects.end());
    return suspects;
}

std::vector<std::size_t> batch_culprit_candidates(const BatchResult& br,
                                                  const std::vector<std::size_t>& suspects,
                                                  std::size_t cases) {
    std::vector<std::size_t> candidates;
    std::vector<bool> seen(cases, false);
    for (std::size_t pos = 0;; ++pos) {
        bool any = false;
        for (const LaneBreak& b : br.breaks) {
            if (pos >= b.unanswered.size()) continue;
            any = true;
            const std::size_t ci = b.unanswered[pos];
            if (!seen[ci]) candidates.push_back(ci);
            seen[ci] = true;
        }
        if (!any) break;
    }
    for (std::size_t ci : suspects)
        if (!seen[ci]) candidates.push_back(ci);
    return candidates;
}

}  // namespace mbstorm::netfuzz
