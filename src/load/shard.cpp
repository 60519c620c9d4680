#include "load/shard.hpp"

#include <fmt/format.h>

#include "load/plan.hpp"
#include "load/rng.hpp"
#include "load/thread_share.hpp"

namespace mbstorm::load {
namespace {

// Keeps the shards' generator seeds apart from the engine's per-thread derivations.
constexpr std::uint64_t kShardSeedDomain = 0x5348'4152'4400'0000ULL;  // "SHARD"

// Where shard `index` of `count` starts walking the operation's range: the range's blocks
// dealt out evenly, so the shards together begin spread over it.
std::uint32_t sequential_start(const Operation& op, std::uint32_t index, std::uint32_t count) {
    const std::uint32_t positions =
        static_cast<std::uint32_t>(last_start_address(op)) - op.first_address + 1;
    const std::uint32_t stride = address_span(op);
    const std::uint64_t blocks = (positions + stride - 1) / stride;
    return static_cast<std::uint32_t>(blocks * index / count) * stride;
}

Error refused(std::string why) {
    return Error(ErrorCode::InvalidInput, std::move(why));
}

}  // namespace

Result<Plan> shard_plan(const Plan& plan, std::uint32_t index, std::uint32_t count) {
    if (count < 1 || count > kMaxShards)
        return refused(
            fmt::format("shard count {} is out of range (valid 1..{})", count, kMaxShards));
    if (index >= count)
        return refused(fmt::format("shard index {} is out of range for {} shards (valid 0..{})",
                                   index, count, count - 1));
    Plan p = plan;
    p.shard = {index, count};
    if (count == 1) return p;

    auto share = [&](std::uint64_t total) { return thread_share(total, count, index); };
    const std::string who = fmt::format("shard {}/{}", index, count);
    p.connections = static_cast<std::uint32_t>(share(plan.connections));
    if (p.connections == 0) {
        return refused(fmt::format(
            "{} gets 0 of the plan's {} connection{}: every shard needs one (use at most {} "
            "shards)",
            who, plan.connections, plan.connections == 1 ? "" : "s", plan.connections));
    }
    if (plan.transactions != 0) {
        p.transactions = share(plan.transactions);
        if (p.transactions == 0) {
            return refused(fmt::format(
                "{} gets 0 of the plan's {} transactions: every shard needs one (use at most {} "
                "shards)",
                who, plan.transactions, plan.transactions));
        }
    }
    // Rates follow the connections: each connection paces what it would on one machine.
    const double fraction = static_cast<double>(p.connections) / plan.connections;
    p.rate = plan.rate * fraction;
    p.connect_rate = plan.connect_rate * fraction;

    // Stages: the one-machine values as the schedule walks them (unset keeps the previous).
    std::uint32_t whole_connections = plan.connections;
    double whole_rate = plan.rate;
    for (Stage& stage : p.stages) {
        whole_connections = stage.target_connections.value_or(whole_connections);
        whole_rate = stage.target_rate.value_or(whole_rate);
        const auto mine = static_cast<std::uint32_t>(share(whole_connections));
        if (stage.target_connections) stage.target_connections = mine;
        // Set on every stage: the shard's share of the rate moves with its share of the
        // connections even where the whole plan's rate stays. Linear in both ends, so the
        // shards' ramps add up to the whole plan's at every moment.
        if (plan.model == LoadModel::OpenLoop) {
            stage.target_rate = whole_connections == 0 ? whole_rate * fraction
                                                       : whole_rate * mine / whole_connections;
        }
    }
    p.seed = derive_seed(plan.seed ^ kShardSeedDomain, index);
    for (Operation& op : p.operations) {
        if (op.address_mode == AddressMode::Sequential)
            op.start_offset = op.start_offset + sequential_start(op, index, count);
    }
    return p;
}

}  // namespace mbstorm::load
