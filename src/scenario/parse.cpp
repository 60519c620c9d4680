// Top level of a scenario file; operations are in operation_yaml.cpp.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include "net/socket.hpp"
#include "net/source_addresses.hpp"
#include "scenario/operation_names.hpp"
#include "scenario/operation_yaml.hpp"
#include "scenario/scenario.hpp"
#include "scenario/yaml_reader.hpp"
#include "yaml/positioned_error.hpp"

namespace mbstorm::scenario {
namespace {

using namespace std::chrono_literals;

constexpr load::Duration kMaxRunTime = std::chrono::hours(24 * 366);

std::string stem_of(std::string_view source) {
    std::string s(source);
    if (const auto slash = s.find_last_of('/'); slash != std::string::npos) s.erase(0, slash + 1);
    if (const auto dot = s.find_last_of('.'); dot != std::string::npos && dot > 0) s.erase(dot);
    return s;
}

StageSpec parse_stage(const YamlReader& r, const YAML::Node& n, std::size_t index) {
    StageSpec st;
    st.name = fmt::format("stage {}", index + 1);
    const std::string what = fmt::format("stages[{}]", index);
    bool has_duration = false;
    r.each_key(n, what, {"name", "duration", "rate", "connections", "ramp"},
               [&](const std::string& key, const YAML::Node&, const YAML::Node& v) {
                   if (key == "name")
                       st.name = r.scalar(v, "name");
                   else if (key == "duration") {
                       st.duration = r.duration(v, "stage duration", 0s, kMaxRunTime, true);
                       has_duration = true;
                   } else if (key == "rate") {
                       st.rate = r.number(v, "stage rate (transactions/s)", 0, load::kMaxRate);
                   } else if (key == "connections") {
                       st.connections = static_cast<std::uint32_t>(
                           r.integer(v, "stage connections", 0, load::kMaxConnections));
                   } else {
                       st.ramp = r.choice(v, "ramp", {"linear", "constant"}) == "constant"
                                     ? load::Ramp::Constant
                                     : load::Ramp::Linear;
                   }
               });
    if (!has_duration) r.fail(n, what + ": `duration` is required (valid > 0s, e.g. 30s)");
    return st;
}

void check_target(const YamlReader& r, const YAML::Node& n, const std::string& text) {
    if (const Result<Target> target = parse_target(text); !target.ok())
        r.fail(n, "target: " + target.error().message());
}

}  // namespace

load::Duration Scenario::total_duration() const noexcept {
    if (stages.empty()) return plan.duration;
    load::Duration total{};
    for (const auto& s : stages) total += s.duration;
    return total;
}

Result<Target> parse_target(const std::string& text) {
    const std::string forms =
        "HOST, HOST:PORT, [IPv6]:PORT or an IPv6 address; port 502 if omitted";
    Target target;
    std::uint16_t p = 502;
    const Error split_error = net::split_host_port(text, target.host, p);
    const bool split = split_error.ok();
    if (!split && split_error.message().rfind("bad port", 0) != 0)
        return Error(ErrorCode::InvalidInput, fmt::format("{} ({})", split_error.text(), forms));
    if (!split || p == 0) {
        return Error(ErrorCode::InvalidInput,
                     fmt::format("'{}': the port must be 1..65535 ({})", text, forms));
    }
    if (target.host.empty()) {
        return Error(ErrorCode::InvalidInput,
                     fmt::format("'{}': the host is empty ({})", text, forms));
    }
    target.port = p;
    return target;
}

namespace {

// The top-level keys whose meaning depends on others: kept to be checked together, and to
// point errors at.
struct TopLevelNodes {
    NodeSlot target, slave, duration, stages, ops, thresholds, model, rate, arrival, transactions,
        backoff;
    bool depth = false;  // given in the file
};

// Reads every top-level key: plain settings into `s`, the rest into the returned slots.
TopLevelNodes read_top_level(const YamlReader& r, const YAML::Node& root, Scenario& s) {
    load::Plan& p = s.plan;
    TopLevelNodes k;
    r.each_key(
        root, "the scenario",
        {"name",           "description",     "target",        "transport",
         "source_addr",    "slave",           "slave_threads", "threads",
         "connections",    "depth",           "model",         "rate",
         "arrival",        "duration",        "transactions",  "warmup",
         "timeout",        "connect_timeout", "connect_rate",  "reconnect_backoff",
         "late_threshold", "allow_writes",    "seed",          "stages",
         "operations",     "thresholds"},
        [&](const std::string& key, const YAML::Node&, const YAML::Node& v) {
            if (key == "name")
                s.name = r.scalar(v, "name");
            else if (key == "description")
                s.description = r.scalar(v, "description");
            else if (key == "target") {
                k.target = v;
                s.target = r.scalar(v, "target");
                check_target(r, v, s.target);
            } else if (key == "transport") {
                // Its own values beside tcp come with each transport (see the README).
                const std::string t = r.scalar(v, "transport");
                if (t == "tcp")
                    p.framing = codec::Framing::Mbap;
                else if (t == "rtu-over-tcp")
                    p.framing = codec::Framing::Rtu;
                else
                    r.fail(v, "transport: '" + t + "' is not one of tcp, rtu-over-tcp");
            } else if (key == "source_addr") {
                p.source_addresses = r.scalar(v, "source_addr");
                if (auto sources = net::parse_source_addresses(p.source_addresses); !sources.ok())
                    r.fail(v, "source_addr: " + sources.error().text());
            } else if (key == "slave")
                k.slave = v;
            else if (key == "slave_threads")
                s.slave_threads = static_cast<unsigned>(r.integer(v, "slave_threads", 0, 1024));
            else if (key == "threads")
                p.threads = static_cast<std::uint32_t>(
                    r.integer(v, "threads (0 = one per core)", 0, load::kMaxThreads));
            else if (key == "connections")
                p.connections = static_cast<std::uint32_t>(
                    r.integer(v, "connections", 1, load::kMaxConnections));
            else if (key == "depth")
                k.depth = true,
                p.depth = static_cast<std::uint32_t>(r.integer(v, "depth", 1, load::kMaxDepth));
            else if (key == "model") {
                k.model = v;
                s.model = r.choice(v, "model", {"closed", "open"}) == "open"
                              ? load::LoadModel::OpenLoop
                              : load::LoadModel::ClosedLoop;
            } else if (key == "rate") {
                k.rate = v;
                p.rate = r.number(v, "rate (transactions/s)", 0, load::kMaxRate);
            } else if (key == "arrival") {
                k.arrival = v;
                p.arrival = r.choice(v, "arrival", {"even", "poisson"}) == "poisson"
                                ? load::Arrival::Poisson
                                : load::Arrival::Even;
            } else if (key == "duration") {
                k.duration = v;
                p.duration = r.duration(v, "duration", 0s, kMaxRunTime);
            } else if (key == "transactions") {
                k.transactions = v;
                p.transactions = static_cast<std::uint64_t>(
                    r.integer(v, "transactions", 0, std::int64_t{1} << 62));
            } else if (key == "warmup") {
                p.warmup = r.duration(v, "warmup", 0s, kMaxRunTime);
            } else if (key == "timeout")
                p.transaction_timeout = r.duration(v, "timeout", 1ms, 1h);
            else if (key == "connect_timeout")
                p.connect_timeout = r.duration(v, "connect_timeout", 0s, 1h, true);
            else if (key == "connect_rate")
                p.connect_rate = r.number(v, "connect_rate (connections/s)", 1, 1e7);
            else if (key == "reconnect_backoff") {
                k.backoff = v;
                r.each_key(v, "reconnect_backoff", {"min", "max"},
                           [&](const std::string& k, const YAML::Node&, const YAML::Node& d) {
                               (k == "min" ? p.reconnect_backoff_min : p.reconnect_backoff_max) =
                                   r.duration(d, "reconnect_backoff." + k, 0s, 1h);
                           });
            } else if (key == "late_threshold")
                p.late_threshold = r.duration(v, "late_threshold", 0s, 1h);
            else if (key == "allow_writes")
                p.allow_writes = r.boolean(v, "allow_writes");
            else if (key == "seed")
                p.seed = static_cast<std::uint64_t>(r.integer(v, "seed", 0, std::int64_t{1} << 62));
            else if (key == "stages")
                k.stages = v;
            else if (key == "operations")
                k.ops = v;
            else if (key == "thresholds")
                k.thresholds = v;
        });

    return k;
}

// The operations, their names made unique, and their per-operation expectations and
// thresholds. Returns the names, which overall thresholds refer to.
OperationNames parse_operations(const YamlReader& r, const YAML::Node& root, const TopLevelNodes& k,
                                Scenario& s) {
    load::Plan& p = s.plan;
    if (!k.ops) r.fail(root, "`operations` is required: a list of at least one operation");
    if (!k.ops.node.IsSequence() || k.ops.node.size() == 0) {
        r.fail(k.ops, "operations must be a list of at least one operation");
    }
    if (k.ops.node.size() > kMaxOperations) {
        r.fail(k.ops.node[kMaxOperations], fmt::format("too many operations: {} (at most {})",
                                                       k.ops.node.size(), kMaxOperations));
    }
    OperationNames names;
    std::vector<ParsedOperation> parsed;
    parsed.reserve(k.ops.node.size());
    for (std::size_t i = 0; i < k.ops.node.size(); ++i) {
        parsed.push_back(parse_operation(r, k.ops.node[i], i));
    }
    // Explicit names must be unique; default names get a suffix when they collide.
    for (std::size_t i = 0; i < parsed.size(); ++i) {
        if (parsed[i].named && !names.add_explicit(parsed[i].operation.name)) {
            r.fail(k.ops.node[i]["name"], fmt::format("operation name '{}' is used twice (names "
                                                      "must be unique)",
                                                      parsed[i].operation.name));
        }
    }
    for (std::size_t i = 0; i < parsed.size(); ++i) {
        auto& op = parsed[i].operation;
        if (!parsed[i].named) op.name = names.add_default(op.name);
        for (auto& t : parsed[i].thresholds) {
            t.operation = op.name;
            t.in_operation = true;
        }
        p.operations.push_back(op);
        s.expectations.push_back(parsed[i].expect);
        s.thresholds.insert(s.thresholds.end(), parsed[i].thresholds.begin(),
                            parsed[i].thresholds.end());
    }

    return names;
}

// Overall thresholds: "p99 < 5ms", or {operation: NAME, check: "p99 < 5ms"}.
void parse_thresholds(const YamlReader& r, const TopLevelNodes& k, const OperationNames& names,
                      Scenario& s) {
    if (k.thresholds) {
        if (!k.thresholds.node.IsSequence()) {
            r.fail(k.thresholds, "thresholds must be a list of expressions like \"p99 < 5ms\"");
        }
        if (k.thresholds.node.size() > kMaxThresholds) {
            r.fail(k.thresholds.node[kMaxThresholds],
                   fmt::format("too many thresholds: {} (at most {})", k.thresholds.node.size(),
                               kMaxThresholds));
        }
        for (const auto& t : k.thresholds.node) {
            NodeSlot expr;
            std::string op_name;
            if (!t.IsMap()) {
                expr = t;
            } else {
                NodeSlot op_node;
                r.each_key(t, "threshold", {"operation", "check"},
                           [&](const std::string& k, const YAML::Node&, const YAML::Node& v) {
                               if (k == "operation") {
                                   op_node = v;
                                   op_name = r.scalar(v, "operation");
                               } else {
                                   expr = v;
                               }
                           });
                if (!expr) r.fail(t, "threshold: `check` is required (e.g. check: p99 < 5ms)");
                if (op_node && !names.contains(op_name)) {
                    r.fail(op_node, fmt::format("threshold: no operation is named '{}' (names: {})",
                                                op_name, fmt::join(names.all(), ", ")));
                }
            }
            Result<ThresholdSpec> spec = parse_threshold(r.scalar(expr, "threshold"));
            if (!spec.ok()) r.fail(expr, spec.error().message());
            spec->operation = op_name;
            s.thresholds.push_back(std::move(spec).value());
        }
    }
}

// Stages, which replace duration and transactions.
void parse_stages(const YamlReader& r, const TopLevelNodes& k, Scenario& s) {
    load::Plan& p = s.plan;
    if (k.stages) {
        if (!k.stages.node.IsSequence() || k.stages.node.size() == 0) {
            r.fail(k.stages, "stages must be a list of at least one stage");
        }
        if (k.stages.node.size() > kMaxStages) {
            r.fail(k.stages.node[kMaxStages], fmt::format("too many stages: {} (at most {})",
                                                          k.stages.node.size(), kMaxStages));
        }
        if (k.duration) {
            r.fail(k.duration,
                   "duration: not used with stages (the run lasts the sum of the "
                   "stage durations); remove it");
        }
        if (k.transactions) {
            r.fail(k.transactions,
                   "transactions: not supported with stages (stages end by "
                   "time); remove it");
        }
        for (std::size_t i = 0; i < k.stages.node.size(); ++i) {
            s.stages.push_back(parse_stage(r, k.stages.node[i], i));
        }
        p.duration = s.total_duration();
    }
}

// The model: open loop when asked for, or when a rate is given anywhere.
void settle_model(const YamlReader& r, const TopLevelNodes& k, Scenario& s) {
    load::Plan& p = s.plan;
    bool stage_rate = false;
    for (std::size_t i = 0; i < s.stages.size(); ++i) {
        if (!s.stages[i].rate) continue;
        stage_rate = true;
        if (s.model == load::LoadModel::ClosedLoop) {
            r.fail(k.stages.node[i]["rate"],
                   "stage rate needs an open-loop scenario (model: open "
                   "or no model key)");
        }
    }
    const load::LoadModelAsked asked{s.model, p.rate, stage_rate, bool(k.arrival)};
    switch (load::settle_load_model(asked, p.model)) {
        case load::LoadModelConflict::None:
            break;
        case load::LoadModelConflict::RateInClosedLoop:
            r.fail(k.rate,
                   "rate: not used in a closed-loop run (model: closed); remove it or "
                   "use model: open");
            break;
        case load::LoadModelConflict::OpenLoopWithoutRate:
            r.fail(k.rate ? k.rate : k.model,
                   fmt::format("rate: an open-loop run needs a rate > 0 (valid > 0..{:g} "
                               "transactions/s)",
                               load::kMaxRate));
            break;
        case load::LoadModelConflict::ArrivalInClosedLoop:
            r.fail(k.arrival,
                   "arrival: only used in an open-loop run, which a rate sets (model: closed or "
                   "no rate); remove it or set rate");
            break;
    }
}

// Length of the run, and the reconnect backoff's order.
void check_run_length(const YamlReader& r, const TopLevelNodes& k, Scenario& s) {
    const load::Plan& p = s.plan;
    if (s.stages.empty() && p.duration == load::Duration::zero() && p.transactions == 0) {
        r.fail(k.duration,
               "duration: 0s never ends the run (valid > 0s, or 0s with transactions >= 1)");
    }
    if (k.backoff && p.reconnect_backoff_max < p.reconnect_backoff_min) {
        r.fail(k.backoff, fmt::format("reconnect_backoff: max {} is below min {} (need min <= "
                                      "max)",
                                      duration_text(p.reconnect_backoff_max),
                                      duration_text(p.reconnect_backoff_min)));
    }
}

// The embedded slave: a device model, only without a target.
void parse_embedded_slave(const YamlReader& r, const TopLevelNodes& k, std::string_view source,
                          Scenario& s) {
    if (k.slave) {
        if (k.target) {
            r.fail(k.slave,
                   "slave: only used with the embedded slave; remove `target` or "
                   "`slave`");
        }
        // A DeviceYamlError, placed in this file, passes to parse_scenario's edge.
        s.slave = slave::parse_device_node(k.slave, source);
        s.slave_given = true;
    }
}

// Throws the readers' yaml::PositionedError (a ScenarioError, or a DeviceYamlError from the
// embedded slave's section); parse_scenario turns it into an Error.
Scenario parse_or_throw(std::string_view text, std::string_view source) {
    const YamlReader r{std::string(source)};
    YAML::Node root;
    try {
        root = YAML::Load(std::string(text));
    } catch (const YAML::Exception& e) {
        r.fail(e.mark, "YAML syntax: " + e.msg);
    }
    if (!root || root.IsNull()) {
        r.fail(YAML::Mark::null_mark(), "the scenario is empty (give at least `operations:`)");
    }
    if (!root.IsMap())
        r.fail(root, "a scenario must be a mapping of keys (target, operations, ...)");

    Scenario s;
    s.source = std::string(source);
    s.name = stem_of(source);
    load::Plan& p = s.plan;
    p.connections = kDefaultConnections;
    p.depth = kDefaultDepth;
    p.operations.clear();

    try {
        const TopLevelNodes k = read_top_level(r, root, s);
        // RTU over TCP has no transaction ids: one request at a time unless the file says.
        if (s.plan.framing == codec::Framing::Rtu && !k.depth) s.plan.depth = 1;
        const OperationNames names = parse_operations(r, root, k, s);
        parse_thresholds(r, k, names, s);
        parse_stages(r, k, s);
        settle_model(r, k, s);
        check_run_length(r, k, s);
        parse_embedded_slave(r, k, source, s);
    } catch (const YAML::Exception& e) {  // e.g. a conversion yaml-cpp refused
        r.fail(e.mark, e.msg);
    }

    // Anything the engine would still refuse (a backstop: the checks above come first).
    if (const Error problems = validate_scenario(s); !problems.ok())
        r.fail(root, problems.message().substr(0, problems.message().find('\n')));  // the first
    return s;
}

// The reader's message is "<place>: <message>" (yaml::Reader::fail): split it back, so the
// text users see stays the same and the place is the Error's.
Error positioned(const yaml::PositionedError& e, std::string_view source) {
    std::string place(source);
    if (e.line() > 0) place += fmt::format(":{}:{}", e.line(), e.column());
    const std::string_view text = e.what();
    if (text.size() > place.size() + 2 && text.starts_with(place) &&
        text.substr(place.size(), 2) == ": ") {
        return Error(ErrorCode::InvalidInput, std::string(text.substr(place.size() + 2)), place);
    }
    return Error(ErrorCode::InvalidInput, std::string(text));
}

}  // namespace

Result<Scenario> parse_scenario(std::string_view text, std::string_view source) {
    try {
        return parse_or_throw(text, source);
    } catch (const yaml::PositionedError& e) {  // this layer's edge: no exception leaves it
        return positioned(e, source);
    }
}

Result<Scenario> load_scenario_file(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return Error(open_failure(path), "cannot open the scenario file", path);
    // Read at most one chunk past the cap: a huge file is refused without being loaded.
    std::string text;
    char chunk[64 * 1024];
    while (text.size() <= kMaxScenarioBytes && in.read(chunk, sizeof chunk).gcount() > 0)
        text.append(chunk, static_cast<std::size_t>(in.gcount()));
    if (text.size() > kMaxScenarioBytes) {
        return Error(ErrorCode::InvalidInput,
                     fmt::format("the scenario file is larger than {} MiB (a scenario is a few "
                                 "kilobytes; is this the right file?)",
                                 kMaxScenarioBytes >> 20),
                     path + ":1:1");
    }
    return parse_scenario(text, path);
}

}  // namespace mbstorm::scenario
