// A scenario: a load test described once in YAML (scenarios/README.md documents every key).
// Parsing resolves it to plain data: the engine's load::Plan, the staged schedule, the
// thresholds, the read-back checks and the embedded slave's settings. Every problem found in
// a file is an Error whose place is "<file>:<line>:<column>" (so its text() starts with it);
// the YAML readers' exceptions stay inside the layer (yaml_reader.hpp).
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "load/plan.hpp"
#include "scenario/expect.hpp"
#include "scenario/threshold.hpp"
#include "slave/device_yaml.hpp"
#include "util/error.hpp"

namespace mbstorm::scenario {

// One stage of a staged run. `rate` / `connections` are the values reached at the end of the
// stage; a linear stage ramps to them from the previous stage's end (the first stage from the
// top-level values), a constant stage holds them for its whole duration.
struct StageSpec {
    std::string name;  // default "stage N"
    load::Duration duration{};
    std::optional<double> rate;                // open loop: transactions per second
    std::optional<std::uint32_t> connections;  // open or closed loop
    load::Ramp ramp = load::Ramp::Linear;
    bool operator==(const StageSpec&) const = default;
};

// Caps on what a scenario file may ask for, each refused with its file:line:column: a file
// past them is a mistake or an attack (each operation costs histograms on every thread).
inline constexpr std::size_t kMaxScenarioBytes = 4u << 20;
inline constexpr std::size_t kMaxOperations = 1000;
inline constexpr std::size_t kMaxStages = 1000;
inline constexpr std::size_t kMaxThresholds = 1000;    // overall, and per operation
inline constexpr std::size_t kMaxListEntries = 65536;  // values.pattern, expect.values

inline constexpr std::uint32_t kDefaultConnections = 16;
inline constexpr std::uint32_t kDefaultDepth = 16;

struct Scenario {
    std::string source;  // file name (for messages)
    std::string name;    // default: the file name without directory and extension
    std::string description;

    // Empty: run against the embedded reference slave (configured by `slave`).
    std::string target;
    load::Plan plan;  // host/port filled once the target is known (see runner)
    // Model asked for explicitly (`model:`); otherwise open loop when a rate is given.
    std::optional<load::LoadModel> model;

    std::vector<StageSpec> stages;

    std::vector<ThresholdSpec> thresholds;  // overall and per operation
    std::vector<Expectation> expectations;  // one per operation (may be inactive)

    // The embedded slave (used only when `target` is empty).
    slave::DeviceDescription slave;
    bool slave_given = false;    // the file had a `slave:` section (noted when unused)
    unsigned slave_threads = 0;  // 0: half the cores

    // Sum of the stage durations, or plan.duration when there are no stages.
    load::Duration total_duration() const noexcept;
};

// Parses scenario text. An InvalidInput error for unknown keys, wrong types, out-of-range
// values, each placed at "<source>:<line>:<column>" and naming the valid range. The scenario
// passes validate_scenario().
Result<Scenario> parse_scenario(std::string_view text, std::string_view source = "<scenario>");
// The file parsed; NotFound or Io (placed at the path) when it cannot be read.
Result<Scenario> load_scenario_file(const std::string& path);

// Values given on the command line; each set one replaces the file's value.
struct Overrides {
    std::optional<std::string> target;
    std::optional<std::string> source_addresses;
    std::optional<load::Duration> duration;  // with stages: the stages are scaled to fit
    std::optional<load::Duration> warmup;
    std::optional<std::uint32_t> connections;
    std::optional<std::uint32_t> depth;
    std::optional<codec::Framing> framing;  // --transport (depth 1 for RTU unless --depth)
    std::optional<std::uint32_t> threads;
    std::optional<double> rate;  // also switches an unstaged closed-loop scenario to open loop
    std::optional<std::uint64_t> transactions;
    std::optional<load::Duration> transaction_timeout;
    std::optional<load::Duration> connect_timeout;
    std::optional<double> connect_rate;
    std::optional<std::uint64_t> seed;
    std::optional<unsigned> slave_threads;
    bool allow_writes = false;
};

// Applies the overrides and re-checks the result: Error::none() when usable, else an
// InvalidInput error listing every problem, one per line.
Error apply_overrides(Scenario& scenario, const Overrides& overrides);

// Whole-scenario checks that span keys (the plan, stages against the model), as
// apply_overrides reports them.
Error validate_scenario(const Scenario& scenario);

// Builds the scenario a flag-only `mbstorm run` amounts to (for --print-scenario).
Scenario scenario_from_plan(const load::Plan& plan, const std::string& target);

struct Target {
    std::string host;
    std::uint16_t port = 502;
};

// Parses a target (net::split_host_port's syntax; port 502 when omitted) into host and port;
// an InvalidInput error naming the accepted forms.
Result<Target> parse_target(const std::string& text);

}  // namespace mbstorm::scenario
