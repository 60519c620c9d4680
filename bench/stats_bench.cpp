// Hot-path costs of the stats layer: Histogram::record, percentile queries, merging.
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

#include "stats/counters.hpp"
#include "stats/histogram.hpp"
#include "stats/interval_recorder.hpp"

namespace {

using mbstorm::stats::Histogram;

// Log-uniform latencies between 1 µs and 1 s: every bucket gets exercised.
std::vector<std::uint64_t> random_latencies(std::size_t n, std::uint64_t seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> exponent(3.0, 9.0);
    std::vector<std::uint64_t> values(n);
    for (auto& v : values) v = static_cast<std::uint64_t>(std::pow(10.0, exponent(rng)));
    return values;
}

Histogram filled_histogram(std::size_t n, std::uint64_t seed) {
    Histogram h;
    for (auto v : random_latencies(n, seed)) h.record(v);
    return h;
}

void BM_HistogramRecord(benchmark::State& state) {
    const auto values = random_latencies(1 << 16, 1);
    Histogram h;
    std::size_t i = 0;
    for (auto _ : state) {
        h.record(values[i]);
        i = (i + 1) & (values.size() - 1);
    }
    benchmark::DoNotOptimize(h.total_count());
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_HistogramRecord);

void BM_HistogramRecordCorrectedNoBackfill(benchmark::State& state) {
    const auto values = random_latencies(1 << 16, 2);
    Histogram h;
    std::size_t i = 0;
    for (auto _ : state) {
        h.record_corrected(values[i], 2'000'000'000);  // interval above every value
        i = (i + 1) & (values.size() - 1);
    }
    benchmark::DoNotOptimize(h.total_count());
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_HistogramRecordCorrectedNoBackfill);

void BM_OutcomeCountersRecord(benchmark::State& state) {
    mbstorm::stats::OutcomeCounters c;
    for (auto _ : state) {
        c.record(mbstorm::stats::Outcome::Ok);
        benchmark::ClobberMemory();
    }
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_OutcomeCountersRecord);

void BM_IntervalRecorderRecordAndTick(benchmark::State& state) {
    const auto values = random_latencies(1 << 16, 3);
    mbstorm::stats::IntervalTimeline timeline(1'000'000'000, 1, 1 << 20);
    mbstorm::stats::IntervalRecorder rec(1'000'000'000);
    std::size_t i = 0;
    std::uint64_t now = 0;
    for (auto _ : state) {
        now += 1000;  // 1 µs of simulated time per transaction: a tick every 1M records
        rec.tick(now, timeline, 0);
        rec.record_latency(values[i]);
        rec.record_transaction(false);
        i = (i + 1) & (values.size() - 1);
    }
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_IntervalRecorderRecordAndTick);

void BM_ValueAtPercentile(benchmark::State& state) {
    const Histogram h = filled_histogram(1'000'000, 4);
    const double p = static_cast<double>(state.range(0)) / 1000.0;
    for (auto _ : state) benchmark::DoNotOptimize(h.value_at_percentile(p));
}
BENCHMARK(BM_ValueAtPercentile)->Arg(50'000)->Arg(99'900);

void BM_Merge(benchmark::State& state) {
    const Histogram other = filled_histogram(1'000'000, 5);
    Histogram into;
    for (auto _ : state) {
        into.add(other);
        benchmark::DoNotOptimize(into.total_count());
    }
    state.SetBytesProcessed(state.iterations() *
                            static_cast<std::int64_t>(other.counts_length() * 8));
}
BENCHMARK(BM_Merge);

void BM_PercentileDistribution(benchmark::State& state) {
    const Histogram h = filled_histogram(1'000'000, 6);
    for (auto _ : state) benchmark::DoNotOptimize(mbstorm::stats::percentile_distribution(h));
}
BENCHMARK(BM_PercentileDistribution);

}  // namespace
