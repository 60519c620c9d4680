// Runs a scenario: the embedded reference slave when there is no target, then one engine run
// (stages are run natively by the engine), then the thresholds.
#include "scenario/runner.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <memory>
#include <thread>

#include "codec/function_code.hpp"
#include "scenario/expect.hpp"
#include "scenario/print.hpp"
#include "server/server.hpp"
#include "slave/device_yaml.hpp"

namespace mbstorm::scenario {

namespace {

// What was asked of the target, for the report's header: the function, where, how much, which
// unit ("request: 0x03 read_holding_registers, addresses 0-99 sequential, quantity 10, unit 1").
std::string describe_request(const load::Operation& op) {
    const bool range = op.last_address && *op.last_address != op.first_address;
    const std::string where =
        range ? fmt::format("addresses {}-{} {}", op.first_address, *op.last_address,
                            address_mode_name(op.address_mode))
              : fmt::format("address {}", op.first_address);
    const std::string label = codec::function_label(op.function);
    const bool named = !op.name.empty() && label.find(op.name) == std::string::npos;
    return fmt::format("request{}: {}, {}, quantity {}, unit {}",
                       named ? " '" + op.name + "'" : std::string(), label, where, op.quantity,
                       op.unit_id);
}

}  // namespace

load::Plan engine_plan(const Scenario& s) {
    load::Plan plan = s.plan;
    plan.stages.clear();
    for (const StageSpec& st : s.stages) {
        load::Stage stage;
        stage.name = st.name;
        stage.duration = st.duration;
        stage.target_rate = st.rate;
        stage.target_connections = st.connections;
        stage.ramp = st.ramp;
        plan.stages.push_back(std::move(stage));
    }
    return plan;
}

Result<load::Plan> engine_plan(const Scenario& s, load::Plan::Shard shard) {
    if (shard.count == 0) return engine_plan(s);
    return load::shard_plan(engine_plan(s), shard.index, shard.count);
}

void evaluate_thresholds(const Scenario& s, stats::RunResult& run) {
    run.thresholds.clear();
    for (const auto& spec : s.thresholds) run.thresholds.push_back(evaluate_threshold(spec, run));
    // Thresholds judge the load the plan describes: on a run that fell short of it (fewer
    // connections, a lower rate, a shorter time) a pass would be a verdict on another test.
    if (!run.thresholds.empty() && !run.shortfalls.empty()) {
        stats::ThresholdResult carried_out;
        carried_out.expression = "plan carried out";
        carried_out.observed = static_cast<double>(run.shortfalls.size());
        for (const auto& shortfall : run.shortfalls) {
            if (!carried_out.observed_text.empty()) carried_out.observed_text += "; ";
            carried_out.observed_text += shortfall.text;
        }
        run.thresholds.push_back(std::move(carried_out));
    }
}

load::LoadResult run_scenario(const Scenario& s, const RunHooks& hooks) {
    load::LoadResult out;
    Result<load::Plan> part = engine_plan(s, hooks.shard);
    if (!part.ok()) {
        out.error = std::move(part).error();
        return out;
    }
    load::Plan plan = std::move(part).value();
    auto say = [&hooks](const std::string& m) {
        if (hooks.on_message) hooks.on_message(m);
    };

    // One event source for the engine and the embedded slave, chosen (and said) once.
    net::BackendDecision backend;
    if (plan.serial.device.empty()) {
        Result<net::BackendDecision> chosen = net::choose_backend(hooks.backend, true);
        if (!chosen.ok()) {
            out.error = chosen.error();
            return out;
        }
        backend = *chosen;
        say(backend.why.empty() ? fmt::format("backend: {}", net::backend_name(backend.backend))
                                : fmt::format("backend: epoll; {}", backend.why));
    }
    const net::BackendChoice chosen = backend.backend == net::Backend::Epoll
                                          ? net::BackendChoice::Epoll
                                          : net::BackendChoice::IoUring;
    // The embedded slave's models must outlive the server: declared first, destroyed last.
    std::unique_ptr<slave::UnitModels> units;
    std::unique_ptr<server::Server> embedded;
    if (!plan.serial.device.empty()) {
        // run --serial: the line is the target (load/serial_load.hpp).
    } else if (s.target.empty()) {
        const unsigned cores = std::max(1U, std::thread::hardware_concurrency());
        units = std::make_unique<slave::UnitModels>(slave::build_units(s.slave));
        server::ServerConfig sc;
        sc.listen = "127.0.0.1:0";
        sc.framing = plan.framing;  // the slave speaks what the engine speaks
        // Split the cores between the engine and the slave unless told otherwise.
        sc.threads = s.slave_threads != 0 ? s.slave_threads : std::max(1U, cores / 2);
        if (plan.threads == 0) plan.threads = std::max(1U, cores - std::min(cores - 1, sc.threads));
        sc.max_connections = 0;
        sc.faults = s.slave.faults;
        sc.units = units.get();
        sc.simulated = s.slave.simulated;
        sc.backend_choice = chosen;
        embedded = std::make_unique<server::Server>(sc);
        if (Error error = embedded->start(); !error.ok()) {
            out.error =
                Error(error.code(), "cannot start the embedded reference slave: " + error.text());
            return out;
        }
        plan.host = "127.0.0.1";
        plan.port = embedded->port();
        // The caller's first line already said there is no target: this adds where it listens.
        say(fmt::format("embedded reference slave listening on {} ({} thread{})",
                        embedded->endpoint(), embedded->threads(),
                        embedded->threads() == 1 ? "" : "s"));
    } else {
        const Result<Target> target = parse_target(s.target);
        if (!target.ok()) {
            out.error = Error(ErrorCode::InvalidInput, "target: " + target.error().message());
            return out;
        }
        plan.host = target->host;
        plan.port = target->port;
    }

    load::EngineOptions eo;
    eo.stop = hooks.stop;
    eo.tool_version = hooks.tool_version;
    eo.verifier = make_verifier(s.expectations);

    eo.on_progress = hooks.on_progress;
    eo.on_interval_histograms = hooks.on_interval_histograms;
    eo.live = hooks.live;
    eo.on_interval = hooks.on_interval;
    eo.start_at = hooks.start_at;
    eo.backend = hooks.backend;  // decides as above (the features are probed once), and says why
    out = load::run_load(plan, eo);

    for (const load::Operation& op : plan.operations)
        out.run.metadata.notes.push_back(describe_request(op));
    if (embedded) {
        out.run.metadata.notes.push_back(fmt::format(
            "target: embedded reference slave on {} ({} thread{}): it shares this machine's {} "
            "cores with the load, so the numbers measure both (--target for a device's own)",
            embedded->endpoint(), embedded->threads(), embedded->threads() == 1 ? "" : "s",
            std::max(1u, std::thread::hardware_concurrency())));
        embedded->stop();
    } else if (s.slave_given) {
        out.run.metadata.notes.push_back("slave: settings not used (a target was given)");
    }
    if (!s.name.empty()) out.run.metadata.notes.push_back("scenario: " + s.name);
    evaluate_thresholds(s, out.run);
    return out;
}

}  // namespace mbstorm::scenario
