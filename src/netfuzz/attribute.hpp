// The attribute stage of a campaign: what a pipelined batch showed, put on the cases that
// showed it. Verdicts of root causes already known are hits of their findings; a broken lane
// whose break matches a known root cause needs no re-run; the rest are suspects, to be run
// alone. When the target died or hung as a whole, the candidates are every unanswered frame,
// lane by lane in turn from where each broke. Pure decisions over the batch's result: the
// campaign runs what this stage names.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "netfuzz/batch.hpp"

namespace mbstorm::netfuzz {

// How the target takes a frame whose MBAP length disagrees with its PDU's, once asked
// (Campaign::ask_how_length_mismatch_closes).
enum class LengthMismatchClose { NotAsked, RefusesTheFrame, LosesTheStream };

// The root-cause keys a lane break may be, most specific first (the executor's order: see
// CaseRunner::silence_rule).
std::vector<std::string> lane_break_keys(const LaneBreak& b, LengthMismatchClose how);

// Whether a root cause is known; given the case it was seen on, so that it counts as a hit.
using KnownVerdict = std::function<bool(const Verdict& v, std::size_t case_index)>;
using KnownKey = std::function<bool(const std::string& key, std::size_t case_index)>;

// The batch's suspects, ascending and each once: its own, its verdicts of unknown root cause,
// less the cases of lane breaks a known root cause explains.
std::vector<std::size_t> triage(const BatchResult& br, LengthMismatchClose how,
                                const KnownVerdict& known_verdict, const KnownKey& known_key);

// A target that died or hung as a whole: the cases to look at one by one, every lane's first
// unanswered frame, then every lane's second, and so on; then the other suspects.
std::vector<std::size_t> batch_culprit_candidates(const BatchResult& br,
                                                  const std::vector<std::size_t>& suspects,
                                                  std::size_t cases);

}  // namespace mbstorm::netfuzz
