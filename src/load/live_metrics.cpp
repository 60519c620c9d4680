#include "load/live_metrics.hpp"

#include "codec/function_code.hpp"

namespace mbstorm::load {

void LiveMetrics::prepare(const Plan& plan, std::uint32_t threads) {
    std::lock_guard lock(mutex_);
    labels_.clear();
    for (const Operation& op : plan.operations) {
        stats::LiveOperation label;
        label.name = op.name.empty() ? std::string(codec::function_name(op.function)) : op.name;
        label.function_code = op.function;
        label.unit_id = op.unit_id;
        labels_.push_back(std::move(label));
    }
    workers_.clear();
    for (std::uint32_t i = 0; i < threads; ++i)
        workers_.push_back(std::make_unique<LiveWorkerCells>(plan.operations.size()));
}

LiveWorkerCells* LiveMetrics::worker(std::uint32_t index) noexcept {
    std::lock_guard lock(mutex_);
    return index < workers_.size() ? workers_[index].get() : nullptr;
}

void LiveMetrics::set_rates(double target, double achieved) noexcept {
    target_rate_.store(target, std::memory_order_relaxed);
    achieved_rate_.store(achieved, std::memory_order_relaxed);
}

stats::LiveLoad LiveMetrics::snapshot() const {
    stats::LiveLoad out;
    out.test_id = test_id_;
    out.shard = shard_;
    out.target_rate = target_rate_.load(std::memory_order_relaxed);
    out.achieved_rate = achieved_rate_.load(std::memory_order_relaxed);
    out.running = running_.load(std::memory_order_relaxed);
    std::lock_guard lock(mutex_);
    out.operations = labels_;
    for (const auto& w : workers_) {
        for (std::size_t op = 0; op < out.operations.size(); ++op) {
            const LiveOperationCells& from = w->operations[op];
            stats::LiveOperation& into = out.operations[op];
            for (std::size_t i = 0; i < stats::kOutcomeCount; ++i)
                into.counters.outcomes[i] += from.outcomes[i].get();
            for (std::size_t i = 0; i < from.exceptions.size(); ++i)
                into.counters.exceptions[i] += from.exceptions[i].get();
            into.counters.transactions_sent += from.sent.get();
            into.counters.bytes_sent += from.bytes_sent.get();
            into.counters.bytes_received += from.bytes_received.get();
            for (std::size_t i = 0; i < stats::kLatencyBuckets; ++i)
                into.latency_buckets[i] += from.latency_buckets[i].get();
            into.latency_sum_ns += from.latency_sum_ns.get();
        }
        for (std::size_t i = 0; i < stats::kOutcomeCount; ++i)
            out.stray.outcomes[i] += w->stray[i].get();
        out.stray.bytes_received += w->stray_bytes.get();
        out.connections_opened += w->connections_opened.get();
        out.connections_failed += w->connections_failed.get();
        out.connections_closed_by_peer += w->connections_closed_by_peer.get();
        out.open_connections += w->open_connections.get();
        out.in_flight += w->in_flight.get();
        out.tls.handshakes += w->tls_handshakes.get();
        out.tls.resumed += w->tls_resumed.get();
        out.tls.handshake_failures += w->tls_handshake_failures.get();
        out.tls.handshake_ns_total += w->tls_handshake_ns.get();
        out.tls.offloaded += w->tls_offloaded.get();
        out.tls.offload_errors += w->tls_offload_errors.get();
    }
    return out;
}

}  // namespace mbstorm::load
