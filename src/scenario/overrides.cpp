// Command-line overrides and the whole-scenario checks run after them.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>

#include "scenario/runner.hpp"
#include "scenario/scenario.hpp"
#include "scenario/yaml_reader.hpp"

namespace mbstorm::scenario {

namespace {

std::vector<std::string> problems_of(const Scenario& s) {
    std::vector<std::string> problems;
    load::Plan check = engine_plan(s);
    if (s.target.empty()) {
        check.host = "127.0.0.1";
        check.port = 1;  // the embedded slave's port is not known yet
    } else {
        if (const Result<Target> target = parse_target(s.target); target.ok()) {
            check.host = target->host;
            check.port = target->port;
        } else {
            problems.push_back("target: " + target.error().message());
        }
    }
    if (const Error e = load::validate_plan(check); !e.ok()) problems.push_back(e.message());
    if (s.expectations.size() != s.plan.operations.size() && !s.expectations.empty()) {
        problems.push_back("internal: expectations do not match the operations");
    }
    for (const auto& t : s.thresholds) {
        if (t.operation.empty()) continue;
        const bool known =
            std::any_of(s.plan.operations.begin(), s.plan.operations.end(),
                        [&](const load::Operation& op) { return op.name == t.operation; });
        if (!known) {
            problems.push_back(
                fmt::format("threshold '{}': no operation is named '{}'", t.text, t.operation));
        }
    }
    return problems;
}

// Every problem, one per line; none: Error::none().
Error as_error(const std::vector<std::string>& problems) {
    if (problems.empty()) return Error::none();
    return Error(ErrorCode::InvalidInput, fmt::format("{}", fmt::join(problems, "\n")));
}

}  // namespace

Error validate_scenario(const Scenario& s) {
    return as_error(problems_of(s));
}

Error apply_overrides(Scenario& s, const Overrides& o) {
    load::Plan& p = s.plan;
    std::vector<std::string> problems;
    if (o.target) {
        if (const Result<Target> target = parse_target(*o.target); !target.ok()) {
            return Error(ErrorCode::InvalidInput, "--target " + target.error().message());
        }
        s.target = *o.target;
    }
    if (o.duration) {
        if (s.stages.empty()) {
            p.duration = *o.duration;
        } else if (o.duration->count() <= 0) {
            problems.push_back("--duration 0 cannot scale the stages (valid > 0s)");
        } else {
            // Keep the shape of the schedule, compressed or stretched to the new length.
            const double factor = static_cast<double>(o.duration->count()) /
                                  static_cast<double>(s.total_duration().count());
            for (auto& st : s.stages) {
                st.duration = load::Duration(std::max<std::int64_t>(
                    1'000'000, std::llround(static_cast<double>(st.duration.count()) * factor)));
            }
            p.duration = s.total_duration();
        }
    }
    if (o.warmup) p.warmup = *o.warmup;
    if (o.connections) {
        p.connections = *o.connections;
        for (auto& st : s.stages) st.connections.reset();
    }
    if (o.depth) p.depth = *o.depth;
    if (o.framing) {
        p.framing = *o.framing;
        // RTU over TCP has no transaction ids: one request at a time unless --depth says.
        if (p.framing == codec::Framing::Rtu && !o.depth) p.depth = 1;
    }
    if (o.threads) p.threads = *o.threads;
    if (o.rate) {
        p.rate = *o.rate;
        p.model = *o.rate > 0 ? load::LoadModel::OpenLoop : load::LoadModel::ClosedLoop;
        s.model = p.model;
        for (auto& st : s.stages) st.rate.reset();
    }
    if (o.transactions) p.transactions = *o.transactions;
    if (o.transaction_timeout) p.transaction_timeout = *o.transaction_timeout;
    if (o.connect_timeout) p.connect_timeout = *o.connect_timeout;
    if (o.connect_rate) p.connect_rate = *o.connect_rate;
    if (o.source_addresses) p.source_addresses = *o.source_addresses;
    if (o.seed) p.seed = *o.seed;
    if (o.slave_threads) s.slave_threads = *o.slave_threads;
    if (o.allow_writes) p.allow_writes = true;
    for (auto& problem : problems_of(s)) problems.push_back(std::move(problem));
    return as_error(problems);
}

Scenario scenario_from_plan(const load::Plan& plan, const std::string& target) {
    Scenario s;
    s.source = "<command line>";
    s.name = "command-line";
    s.target = target;
    s.plan = plan;
    s.plan.stages.clear();
    s.model = plan.model;
    s.expectations.assign(plan.operations.size(), Expectation{});
    return s;
}

}  // namespace mbstorm::scenario
