// Handler micro-benchmarks: the requests a load test hammers most.
#include <benchmark/benchmark.h>

#include <cstdint>
#include <vector>

#include "slave/data_model.hpp"
#include "slave/handler.hpp"

namespace {

using namespace mbstorm;

void run(benchmark::State& state, const std::vector<std::uint8_t>& request, bool diagnostics) {
    slave::ModelConfig config;
    config.track_diagnostics = diagnostics;
    slave::DataModel model(config);
    std::uint8_t out[slave::kMinOutput];
    for (auto _ : state) {
        const slave::HandleResult r = slave::handle_request(request, model, out);
        benchmark::DoNotOptimize(r);
        benchmark::DoNotOptimize(out);
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
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

}  // namespace

BENCHMARK(BM_Fc03Read10);
BENCHMARK(BM_Fc03Read10NoDiagnostics);
BENCHMARK(BM_Fc10Write10);
BENCHMARK(BM_Fc01Read100);
