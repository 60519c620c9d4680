// `run --shard I/N` and `run --start-at TIME`: the options that let N machines run one test
// (load/shard.hpp divides the plan; mbstorm merge joins the results).
#pragma once

#include <chrono>
#include <string>
#include <string_view>

#include "load/plan.hpp"
#include "util/error.hpp"

namespace mbstorm::cli {

// The environment a Kubernetes Indexed Job gives each pod: its index, and the shard count
// the Job sets (equal to its completions).
inline constexpr const char* kShardIndexEnv = "JOB_COMPLETION_INDEX";
inline constexpr const char* kShardCountEnv = "MBSTORM_SHARD_COUNT";

// The shard from --shard "I/N" (0-based I) or, when the flag is empty, from the environment
// (index and count as given; shard_count empty: not sharded, out.count stays 0). A flag beats
// the environment. An InvalidInput error names where the bad value came from.
Error resolve_shard(const std::string& flag, const char* env_index, const char* env_count,
                    load::Plan::Shard& out);

// How far --start-at may lie from now, either way: further is a typo (or a wrong clock).
inline constexpr std::chrono::hours kMaxStartAtDistance{24};

// --start-at: RFC 3339 with Z or an offset ("2026-11-24T14:00:00Z",
// "2026-11-24T15:00:00.5+01:00") or seconds since the epoch ("1795528800", "1795528800.25").
// A time more than kMaxStartAtDistance from `now` is an error too (InvalidInput).
Error parse_start_at(std::string_view text, std::chrono::system_clock::time_point now,
                     std::chrono::system_clock::time_point& out);

}  // namespace mbstorm::cli
