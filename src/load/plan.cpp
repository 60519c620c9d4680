#include "load/plan.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <thread>

#include "codec/function_code.hpp"
#include "codec/limits.hpp"
#include "net/source_addresses.hpp"

namespace mbstorm::load {
namespace {

namespace lim = codec::limits;

using codec::quantity_range;
using lim::QuantityRange;

std::string seconds_text(Duration d) {
    return fmt::format("{}s", std::chrono::duration<double>(d).count());
}

void check_operation(const Operation& op, std::size_t index, std::vector<std::string>& errors) {
    const std::string where = op.name.empty() ? fmt::format("operations[{}]", index)
                                              : fmt::format("operations[{}] ({})", index, op.name);
    auto fail = [&](std::string what) { errors.push_back(fmt::format("{}: {}", where, what)); };

    if (!is_generatable_function(op.function)) {
        fail(fmt::format("function {} cannot be generated (valid: {})",
                         codec::function_label(op.function), generatable_functions_text()));
        return;
    }
    if (op.weight == 0) fail("weight 0 is out of range (valid 1..4294967295)");

    const QuantityRange q = quantity_range(op.function);
    if (q.max != 0 && (op.quantity < q.min || op.quantity > q.max)) {
        fail(fmt::format("quantity {} is out of range for {} (valid {}..{})", op.quantity,
                         codec::function_name(op.function), q.min, q.max));
    }
    const codec::RequestShape shape = codec::function_info(op.function)->request;
    if (shape == codec::RequestShape::ReadWriteRegisters &&
        (op.write_quantity < 1 || op.write_quantity > lim::kMaxRwWriteRegisters)) {
        fail(fmt::format("write_quantity {} is out of range (valid 1..{})", op.write_quantity,
                         lim::kMaxRwWriteRegisters));
    }
    if (shape == codec::RequestShape::SubFunction && op.sub_function != 0) {
        fail(fmt::format("sub_function {} cannot be generated (valid: 0, return query data)",
                         op.sub_function));
    }
    if (shape == codec::RequestShape::MeiTransport &&
        (op.device_id_code < lim::kMinDeviceIdCode || op.device_id_code > lim::kMaxDeviceIdCode)) {
        fail(fmt::format("device_id_code {} is out of range (valid {}..{})", op.device_id_code,
                         lim::kMinDeviceIdCode, lim::kMaxDeviceIdCode));
    }
    if (codec::function_table(op.function)) {
        const std::uint32_t span = address_span(op);
        const std::uint32_t last_needed = op.first_address + span - 1;
        if (last_needed > 0xFFFF) {
            fail(fmt::format("address {} + quantity {} runs past 65535", op.first_address, span));
        } else if (op.last_address && *op.last_address < last_needed) {
            fail(fmt::format("address range [{}, {}] cannot hold {} items (last must be >= {})",
                             op.first_address, *op.last_address, span, last_needed));
        }
    }
    if (op.address_mode == AddressMode::Zipf &&
        !(op.zipf_exponent > 0 && op.zipf_exponent <= kMaxZipfExponent)) {
        fail(fmt::format("zipf exponent {} is out of range (valid > 0 and <= {})", op.zipf_exponent,
                         kMaxZipfExponent));
    }
    if (codec::is_write_function(op.function) && op.values.mode == ValueMode::Pattern &&
        op.values.pattern.empty()) {
        fail("value pattern is empty (give at least one value)");
    }
}

}  // namespace

bool is_generatable_function(std::uint8_t fc) noexcept {
    const codec::FunctionInfo* f = codec::function_info(fc);
    return f != nullptr && f->request != codec::RequestShape::FileRecords;
}

std::string generatable_functions_text() {
    std::string text;
    for (const codec::FunctionInfo& f : codec::public_functions()) {
        if (!is_generatable_function(codec::to_byte(f.code))) continue;
        if (!text.empty()) text += ", ";
        text += codec::function_label(codec::to_byte(f.code));
    }
    return text;
}

std::uint32_t address_span(const Operation& op) noexcept {
    const codec::FunctionInfo* f = codec::function_info(op.function);
    if (f != nullptr && f->request == codec::RequestShape::ReadWriteRegisters) {
        return std::max(op.quantity, op.write_quantity);
    }
    return std::max<std::uint16_t>(op.quantity, 1);
}

std::uint16_t last_start_address(const Operation& op) noexcept {
    if (!op.last_address) return op.first_address;
    const std::uint32_t span = address_span(op);
    const std::uint32_t last = *op.last_address;
    if (last + 1 < op.first_address + span) return op.first_address;
    return static_cast<std::uint16_t>(last + 1 - span);
}

std::uint32_t peak_connections(const Plan& plan) noexcept {
    std::uint32_t peak = plan.connections;
    for (const Stage& s : plan.stages) peak = std::max(peak, s.target_connections.value_or(0));
    return peak;
}

std::uint32_t effective_threads(const Plan& plan) noexcept {
    std::uint32_t threads = plan.threads;
    if (threads == 0) threads = std::max(1U, std::thread::hardware_concurrency());
    return std::max(1U, std::min(threads, peak_connections(plan)));
}

LoadModelConflict settle_load_model(const LoadModelAsked& asked, LoadModel& model) {
    const bool paced = asked.rate > 0 || asked.stage_rate;
    model = asked.model.value_or(paced ? LoadModel::OpenLoop : LoadModel::ClosedLoop);
    if (model == LoadModel::ClosedLoop && asked.rate > 0)
        return LoadModelConflict::RateInClosedLoop;
    if (model == LoadModel::OpenLoop && !paced) return LoadModelConflict::OpenLoopWithoutRate;
    if (model == LoadModel::ClosedLoop && asked.arrival_given)
        return LoadModelConflict::ArrivalInClosedLoop;
    return LoadModelConflict::None;
}

namespace {

// Each stage of a staged run: its duration and the targets it ramps to.
void check_stages(const Plan& plan, std::vector<std::string>& errors) {
    auto fail = [&](std::string what) { errors.push_back(std::move(what)); };
    for (std::size_t i = 0; i < plan.stages.size(); ++i) {
        const Stage& s = plan.stages[i];
        if (s.duration <= Duration::zero()) {
            fail(fmt::format("stages[{}]: duration {} is out of range (valid > 0s)", i,
                             seconds_text(s.duration)));
        }
        if (s.target_rate && plan.model != LoadModel::OpenLoop) {
            fail(fmt::format("stages[{}]: a target rate needs an open-loop run", i));
        } else if (s.target_rate && !(*s.target_rate >= 0 && *s.target_rate <= kMaxRate)) {
            fail(fmt::format("stages[{}]: target rate {} is out of range (valid 0..{:g})", i,
                             *s.target_rate, kMaxRate));
        }
        if (s.target_connections && *s.target_connections > kMaxConnections) {
            fail(fmt::format("stages[{}]: target connections {} is out of range (valid 0..{})", i,
                             *s.target_connections, kMaxConnections));
        }
    }
}

// Every problem with the plan, each naming its field and valid range.
std::vector<std::string> plan_problems(const Plan& plan) {
    std::vector<std::string> errors;
    auto fail = [&](std::string what) { errors.push_back(std::move(what)); };

    if (plan.host.empty()) fail("target: host is empty");
    if (plan.port == 0) fail("target: port 0 is out of range (valid 1..65535)");
    if (!plan.source_addresses.empty()) {
        if (Result<std::vector<net::Endpoint>> sources =
                net::parse_source_addresses(plan.source_addresses);
            !sources.ok())
            fail("source_addr: " + sources.error().text());
    }

    if (plan.operations.empty()) fail("operations: none given (give at least one)");
    for (std::size_t i = 0; i < plan.operations.size(); ++i) {
        check_operation(plan.operations[i], i, errors);
    }

    if (plan.connections < 1 || plan.connections > kMaxConnections) {
        fail(fmt::format("connections: {} is out of range (valid 1..{})", plan.connections,
                         kMaxConnections));
    }
    if (plan.depth < 1 || plan.depth > kMaxDepth) {
        fail(fmt::format("depth: {} is out of range (valid 1..{})", plan.depth, kMaxDepth));
    }
    if (plan.framing == codec::Framing::Rtu && plan.depth > 1)
        fail(
            fmt::format("depth: {} with RTU over TCP, which has no transaction ids to match "
                        "pipelined answers by (valid: 1; use more connections for more load)",
                        plan.depth));
    if (plan.threads > kMaxThreads) {
        fail(fmt::format("threads: {} is out of range (valid 0..{}, 0 = one per core)",
                         plan.threads, kMaxThreads));
    }
    const bool any_stage_rate =
        std::any_of(plan.stages.begin(), plan.stages.end(),
                    [](const Stage& s) { return s.target_rate && *s.target_rate > 0; });
    if (plan.model == LoadModel::OpenLoop && any_stage_rate) {
        // Staged: the start rate may be 0 (a ramp up from nothing).
        if (!(plan.rate >= 0 && plan.rate <= kMaxRate)) {
            fail(fmt::format("rate: {} is out of range (valid 0..{:g} transactions/s)", plan.rate,
                             kMaxRate));
        }
    } else if (plan.model == LoadModel::OpenLoop && !(plan.rate > 0 && plan.rate <= kMaxRate)) {
        fail(
            fmt::format("rate: {} is out of range for an open-loop run (valid > 0 and <= {:g} "
                        "transactions/s)",
                        plan.rate, kMaxRate));
    }
    if (!(plan.connect_rate > 0 && plan.connect_rate <= 1e7)) {
        fail(
            fmt::format("connect_rate: {} is out of range (valid > 0 and <= 10000000 "
                        "connections/s)",
                        plan.connect_rate));
    }
    if (plan.connect_timeout <= Duration::zero() || plan.connect_timeout > std::chrono::hours(1)) {
        fail(fmt::format("connect_timeout: {} is out of range (valid > 0s and <= 3600s)",
                         seconds_text(plan.connect_timeout)));
    }
    if (plan.transaction_timeout < std::chrono::milliseconds(1) ||
        plan.transaction_timeout > std::chrono::hours(1)) {
        fail(fmt::format("transaction_timeout: {} is out of range (valid 0.001s..3600s)",
                         seconds_text(plan.transaction_timeout)));
    }
    if (plan.reconnect_backoff_min < Duration::zero() ||
        plan.reconnect_backoff_max < plan.reconnect_backoff_min) {
        fail(fmt::format("reconnect backoff: min {} / max {} invalid (need 0 <= min <= max)",
                         seconds_text(plan.reconnect_backoff_min),
                         seconds_text(plan.reconnect_backoff_max)));
    }
    if (plan.duration < Duration::zero()) {
        fail(fmt::format("duration: {} is negative (valid >= 0s)", seconds_text(plan.duration)));
    }
    if (plan.duration == Duration::zero() && plan.transactions == 0 && plan.stages.empty()) {
        fail("duration: the run never ends (give a duration > 0s or a transaction count >= 1)");
    }
    if (plan.warmup < Duration::zero()) {
        fail(fmt::format("warmup: {} is negative (valid >= 0s)", seconds_text(plan.warmup)));
    }
    if (plan.late_threshold < Duration::zero()) {
        fail("late_threshold: negative (valid >= 0s)");
    }
    if (!plan.stages.empty() && plan.transactions != 0) {
        fail("transactions: not supported with stages (stages end by time)");
    }
    check_stages(plan, errors);
    return errors;
}

}  // namespace

Error validate_plan(const Plan& plan) {
    const std::vector<std::string> problems = plan_problems(plan);
    if (problems.empty()) return {};
    return Error(ErrorCode::InvalidInput, fmt::format("{}", fmt::join(problems, "; ")));
}

}  // namespace mbstorm::load
