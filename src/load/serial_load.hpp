// `run --serial`: the load test on a serial line. A bus carries one transaction at a time, so
// this is one blocking master (load/serial_master.hpp) driven by the plan's operations, closed
// loop or paced by --rate, with the same results as a TCP run (latency histograms, outcome
// counters per operation, progress lines) for the same reports.
#pragma once

#include "load/engine.hpp"
#include "load/plan.hpp"

namespace mbstorm::load {

// Precondition: plan.serial.device is set and the plan is valid.
LoadResult run_serial_load(const Plan& plan, const EngineOptions& options);

}  // namespace mbstorm::load
