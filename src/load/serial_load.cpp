#include "load/serial_load.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <vector>

#include "codec/limits.hpp"
#include "codec/mbap.hpp"
#include "load/operation_generator.hpp"
#include "load/response_check.hpp"
#include "load/serial_master.hpp"
#include "net/clock.hpp"

namespace mbstorm::load {
namespace {

stats::Outcome outcome_of(SerialOutcome o) noexcept {
    switch (o) {
        case SerialOutcome::Answered:
        case SerialOutcome::Broadcast:
            return stats::Outcome::Ok;
        case SerialOutcome::Timeout:
            return stats::Outcome::Timeout;
        case SerialOutcome::BadCheck:  // a CRC (RTU) or LRC (ASCII) that fails
            return stats::Outcome::CrcError;
        case SerialOutcome::BadFrame:
            return stats::Outcome::FramingError;
        case SerialOutcome::WrongUnit:
            return stats::Outcome::WrongUnitId;
        case SerialOutcome::IoError:
            return stats::Outcome::ConnectionClosed;
    }
    return stats::Outcome::Malformed;
}

}  // namespace

LoadResult run_serial_load(const Plan& plan, const EngineOptions& options) {
    LoadResult out;
    SerialMaster master;
    if (auto why = master.open(plan.serial.device, plan.serial.line, plan.serial.framing);
        !why.empty()) {
        out.error = why;
        return out;
    }
    stats::RunResult& r = out.run;
    auto& meta = r.metadata;
    meta.tool_version = options.tool_version;
    meta.target = master.describe();
    meta.threads = 1;
    meta.connections = 1;
    meta.depth = 1;
    const bool open_loop = plan.model == LoadModel::OpenLoop && plan.rate > 0;
    meta.model = open_loop ? stats::LoadModel::Open : stats::LoadModel::Closed;
    meta.rate_per_second = open_loop ? plan.rate : 0.0;
    meta.requested_duration_ns = static_cast<std::uint64_t>(plan.duration.count());
    meta.warmup_ns = static_cast<std::uint64_t>(plan.warmup.count());
    meta.start_time = std::chrono::system_clock::now();
    meta.notes.push_back(fmt::format("serial line {}: one request at a time", master.describe()));
    for (const Operation& op : plan.operations) {
        stats::OperationResult o;
        o.name = op.name;
        o.function_code = op.function;
        r.operations.push_back(std::move(o));
    }
    r.connections.opened = 1;
    r.connections.peak_open = 1;

    OperationGenerator generator(plan.operations, plan.seed);
    std::vector<std::uint8_t> adu(max_request_size(plan.operations) + codec::limits::kMbapHeader);
    const std::int64_t start = net::now_ns();
    const std::int64_t measure_from = start + plan.warmup.count();
    const std::int64_t end = plan.duration.count() > 0 ? measure_from + plan.duration.count() : 0;
    const std::int64_t timeout_ns = plan.transaction_timeout.count();
    const std::int64_t interval_ns = open_loop ? static_cast<std::int64_t>(1e9 / plan.rate) : 0;
    const std::int64_t progress_every = std::max<std::int64_t>(options.progress_interval_ns, 1000);
    std::int64_t next_send = start;
    std::int64_t next_progress = measure_from + progress_every;
    std::uint64_t measured_sends = 0, interval_index = 0, interval_errors = 0, interval_done = 0;
    stats::Histogram interval_latency;
    std::uint16_t tid = 0;
    std::uint64_t bad_checks = 0;
    for (;;) {
        if (options.stop && options.stop->load(std::memory_order_relaxed)) break;
        std::int64_t now = net::now_ns();
        if (end != 0 && now >= end) break;
        if (plan.transactions != 0 && measured_sends >= plan.transactions) break;
        if (open_loop) {
            if (next_send > now) net::sleep_until_ns(next_send);
            now = net::now_ns();
            const std::int64_t lag = now - next_send;
            if (lag > plan.late_threshold.count() && now >= measure_from) {
                // The line was busy with the previous transaction: the target's doing.
                auto& l = r.schedule_lag.target;
                ++l.late_sends;
                l.total_lag_ns += static_cast<std::uint64_t>(lag);
                l.max_lag_ns = std::max(l.max_lag_ns, static_cast<std::uint64_t>(lag));
            }
            next_send += interval_ns;
        }
        RequestInfo info;
        const std::size_t size = generator.next(++tid, adu, info);
        if (size <= codec::limits::kMbapHeader) {
            out.error = "the operation could not be encoded";
            return out;
        }
        const codec::Bytes pdu(adu.data() + codec::limits::kMbapHeader,
                               size - codec::limits::kMbapHeader);
        codec::Bytes answer;
        std::int64_t sent_ns = 0;
        const SerialOutcome so = master.transact(info.unit_id, pdu, timeout_ns, answer, sent_ns);
        const std::int64_t done = net::now_ns();
        stats::Outcome outcome = outcome_of(so);
        codec::Response rsp;
        if (so == SerialOutcome::Answered) {
            codec::TcpFrame frame;
            frame.header = {tid, 0, static_cast<std::uint16_t>(answer.size() + 1), info.unit_id};
            frame.pdu = answer;
            outcome = check_response(info, frame, rsp);
            if (outcome == stats::Outcome::Ok && options.verifier.check &&
                !options.verifier.check(options.verifier.context, info, rsp))
                outcome = stats::Outcome::ValueMismatch;
        }
        if (so == SerialOutcome::BadCheck) ++bad_checks;
        if (sent_ns >= measure_from) {
            ++measured_sends;
            auto& op = r.operations[info.op_index];
            for (stats::OutcomeCounters* c : {&r.counters, &op.counters}) {
                ++c->transactions_sent;
                c->bytes_sent += pdu.size() + 3;
                c->bytes_received += answer.size() + 3;
                if (outcome == stats::Outcome::Exception)
                    c->record_exception(static_cast<std::uint8_t>(rsp.exception));
                else
                    c->record(outcome);
            }
            const bool answered =
                outcome == stats::Outcome::Ok || outcome == stats::Outcome::Exception;
            if (answered && so == SerialOutcome::Answered) {
                const auto latency = static_cast<std::uint64_t>(done - sent_ns);
                r.latency.record(latency);
                op.latency.record(latency);
                interval_latency.record(latency);
            }
            ++interval_done;
            if (stats::is_error(outcome)) ++interval_errors;
        }
        if (so == SerialOutcome::IoError) {
            out.error = fmt::format("{}: {}", plan.serial.device, std::strerror(master.io_error()));
            break;
        }
        if (options.on_progress && done >= next_progress) {
            ProgressSnapshot p;
            p.interval_index = interval_index++;
            p.elapsed_seconds = static_cast<double>(done - start) / 1e9;
            p.transactions_per_second =
                static_cast<double>(interval_done) * 1e9 / static_cast<double>(progress_every);
            p.p50_ns = interval_latency.value_at_percentile(50.0);
            p.p99_ns = interval_latency.value_at_percentile(99.0);
            p.max_ns = interval_latency.max();
            p.errors = interval_errors;
            p.total_transactions = r.counters.completed();
            p.open_connections = 1;
            options.on_progress(p);
            interval_latency.reset();
            interval_done = interval_errors = 0;
            next_progress += progress_every;
        }
    }
    const std::int64_t finished = net::now_ns();
    meta.measured_duration_ns =
        finished > measure_from ? static_cast<std::uint64_t>(finished - measure_from) : 0;
    if (bad_checks != 0)
        out.warnings.push_back(
            fmt::format("{} answer{} with a bad {} (counted as malformed)", bad_checks,
                        bad_checks == 1 ? "" : "s",
                        plan.serial.framing == codec::Framing::Ascii ? "LRC" : "CRC"));
    out.ok = out.error.empty();
    return out;
}

}  // namespace mbstorm::load
