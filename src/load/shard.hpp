// Sharding: one plan run by N machines (`mbstorm run --shard I/N`). shard_plan() gives shard I
// its deterministic part, so that the N shards together are the one-machine plan: the same
// totals and the same schedule. Counts (connections, transactions, each stage's connections)
// are split like the engine splits them over its threads, the lowest shards taking the
// remainder (10 over 3: 4, 3, 3); rates follow the connections, so every connection paces the
// same rate as on one machine; each shard seeds its generators apart and starts its sequential
// addresses at its own offset of each range, so the shards do not send the same requests.
#pragma once

#include <cstdint>
#include <string>

#include "load/plan.hpp"
#include "util/error.hpp"

namespace mbstorm::load {

inline constexpr std::uint32_t kMaxShards = kMaxConnections;

// Shard `index` (0-based) of `count`. Refused (InvalidInput) when the shard would get no
// connection or no transaction, or index/count are out of range. plan.shard records the shard.
Result<Plan> shard_plan(const Plan& plan, std::uint32_t index, std::uint32_t count);

}  // namespace mbstorm::load
