// `mbstorm run FILE`: the scenario path of the run command (the logic is in src/scenario/).
#pragma once

#include <chrono>
#include <optional>
#include <string>
#include <vector>

#include "cli/run_output.hpp"
#include "load/plan.hpp"
#include "net/backend.hpp"
#include "scenario/scenario.hpp"
#include "util/error.hpp"

namespace mbstorm::cli {

struct ScenarioRunRequest {
    std::string file;
    bool print = false;  // --print-scenario: print the resolved scenario and exit
    std::string junit;   // --junit FILE
    scenario::Overrides overrides;
    bool quiet = false;
    OutputFiles outputs;
    load::Plan::Shard shard;  // --shard or the environment; count 0: the whole plan
    std::optional<std::chrono::system_clock::time_point> start_at;  // --start-at
    std::shared_ptr<net::TlsContext> tls;                           // --transport tls
    bool tls_resume = false;
    load::Plan::Serial serial;            // --serial: the line replaces the scenario's target
    std::vector<std::string> thresholds;  // --threshold EXPR, added to the scenario's
    bool fail_on_plan_shortfall = false;  // a part of the plan not carried out fails the run
    net::BackendChoice backend = net::BackendChoice::Auto;  // --backend
};

// --threshold expressions added to the scenario's thresholds (the whole run's), or the first
// expression that does not parse, with the forms accepted (InvalidInput).
Error add_threshold_flags(const std::vector<std::string>& texts, scenario::Scenario& s);

// Exit code: 0 all thresholds passed, 1 a threshold breached, 2 usage/configuration error.
int run_scenario_file(const ScenarioRunRequest& request);

// Runs a scenario already loaded (or built from flags): live progress, reports, JUnit and
// the exit code from the thresholds.
int run_resolved_scenario(const scenario::Scenario& s, const ScenarioRunRequest& request);

// --print-scenario for a flag-only run: the plan the flags describe, as a scenario file.
int print_flag_scenario(const load::Plan& plan, const std::string& target,
                        const std::vector<std::string>& thresholds);

}  // namespace mbstorm::cli
