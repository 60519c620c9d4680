// Handler micro-benchmarks: the requests a load test hammers most.
#include <benchmark/benchmark.h>

#include <cstdint>
#include <vector>

#include "slave/data_model.hpp"
#include "slave/handler.hpp"

namespace {

using namespace mbstorm;

void run_on(benchmark::State& state, const std::vector<std::uint8_t>& request,
            slave::DataModel& model) {
    std::uint8_t out[slave::kMinOutput];
    for (auto _ : state) {
        const slave::HandleResult r = slave::handle_request(request, model, out);
        benchmark::DoNotOptimize(r);
        benchmark::DoNotOptimize(out);
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}

void run(benchmark::State& state, const std::vector<std::uint8_t>& request, bool diagnostics) {
    slave::ModelConfig config;
    config.track_diagnostics = diagnostics;
    slave::DataModel model(config);
    run_on(state, request, model);
}

const std::vector<std::uint8_t> kFc3x10 = {0x03, 0x00, 0x64, 0x00, 0x0A};
const std::vector<std::uint8_t> kFc1x100 = {0x01, 0x00, 0x10, 0x00, 0x64};
std::vector<std::uint8_t> fc16x10() {
    std::vector<std::uint8_t> r = {0x10, 0x00, 0x64, 0x00, 0x0A, 0x14};
    for (int i = 0; i < 10; ++i) {
        r.push_back(0x12);
        r.push_back(static_cast<std::uint8_t>(i));
    }
    return r;
}

// Registers are held four to an atomic 64-bit word: a single-register write is a
// compare-and-swap of its word, and a multiple write stores whole words and swaps the partial
// ones at either end.
const std::vector<std::uint8_t> kFc6Write = {0x06, 0x00, 0x65, 0x12, 0x34};
std::vector<std::uint8_t> fc16x3_unaligned() {
    return {0x10, 0x00, 0x65, 0x00, 0x03, 0x06, 0x12, 0x00, 0x12, 0x01, 0x12, 0x02};
}

void BM_Fc03Read10(benchmark::State& s) {
    run(s, kFc3x10, true);
}
void BM_Fc03Read10NoDiagnostics(benchmark::State& s) {
    run(s, kFc3x10, false);
}
void BM_Fc10Write10(benchmark::State& s) {
    run(s, fc16x10(), true);
}
void BM_Fc01Read100(benchmark::State& s) {
    run(s, kFc1x100, true);
}
void BM_Fc06WriteOne(benchmark::State& s) {
    run(s, kFc6Write, true);
}
void BM_Fc10Write3Unaligned(benchmark::State& s) {
    run(s, fc16x3_unaligned(), true);
}
// Two threads writing registers of the same word: the compare-and-swap retries under contention.
slave::DataModel& shared_model() {
    static slave::DataModel model{slave::ModelConfig{}};
    return model;
}
// Reads from two threads of one model: what they share besides the registers (the diagnostics
// counters) shows here.
void BM_Fc03Read10SharedModel(benchmark::State& s) {
    run_on(s, kFc3x10, shared_model());
}
void BM_Fc06WriteOneSharedWord(benchmark::State& s) {
    std::vector<std::uint8_t> request = kFc6Write;
    request[2] = static_cast<std::uint8_t>(0x64 + s.thread_index());
    run_on(s, request, shared_model());
}

}  // namespace

BENCHMARK(BM_Fc03Read10);
BENCHMARK(BM_Fc03Read10NoDiagnostics);
BENCHMARK(BM_Fc10Write10);
BENCHMARK(BM_Fc01Read100);
BENCHMARK(BM_Fc06WriteOne);
BENCHMARK(BM_Fc10Write3Unaligned);
BENCHMARK(BM_Fc03Read10SharedModel)->Threads(1)->Threads(2);
BENCHMARK(BM_Fc06WriteOneSharedWord)->Threads(1)->Threads(2);
