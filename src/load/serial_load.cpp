#include "load/serial_load.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstring>

#include "codec/limits.hpp"
#include "codec/mbap.hpp"
#include "load/operation_generator.hpp"
#include "load/response_check.hpp"
#include "load/result_rows.hpp"
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

// The request and answer as they went on the wire: unit, PDU and CRC (RTU); ASCII frames are
// about twice as long, but the report counts Modbus bytes alike for every framing.
constexpr std::size_t kUnitAndCheck = 3;

}  // namespace

SerialRunner::SerialRunner(const SerialRunSetup& setup)
    : setup_(setup),
      interval_(setup.timeline->interval_ns(), stats::Histogram::kOneHourNs,
                setup.timeline->tags()),
      open_loop_(setup.plan->model == LoadModel::OpenLoop) {
    operations = operation_rows(setup_.plan->operations);
    stages = stage_rows(setup_.schedule->stages(), operations);
}

Error SerialRunner::open() {
    const Plan& plan = *setup_.plan;
    return master_.open(plan.serial.device, plan.serial.line, plan.serial.framing);
}

std::int64_t SerialRunner::pace(std::int64_t now) noexcept {
    const Plan& plan = *setup_.plan;
    const StageSchedule& schedule = *setup_.schedule;
    // Offsets before the end of warm-up read as the first stage's start.
    const StageTargets wanted =
        schedule.empty()
            ? StageTargets{0, plan.rate, 1}
            : schedule.at(next_send_ != 0 && open_loop_ ? next_send_ - setup_.measure_start_ns
                                                        : now - setup_.measure_start_ns);
    // A stage with no connection: the master stays off the line.
    if (wanted.connections == 0 || (open_loop_ && wanted.rate <= 0)) {
        next_send_ = 0;
        return -1;
    }
    if (!open_loop_) return 0;
    if (next_send_ == 0) next_send_ = now;
    return std::max<std::int64_t>(next_send_ - now, 0);
}

void SerialRunner::run() noexcept {
    const Plan& plan = *setup_.plan;
    open_.store(1, std::memory_order_relaxed);
    if (setup_.live != nullptr) {
        setup_.live->connections_opened.add();
        setup_.live->open_connections.set(1);
    }
    if (setup_.start_ns > net::now_ns()) net::sleep_until_ns(setup_.start_ns);  // --start-at

    OperationGenerator generator(plan.operations, plan.seed);
    std::vector<std::uint8_t> adu(max_request_size(plan.operations) + codec::limits::kMbapHeader);
    const std::int64_t measure_from = setup_.measure_start_ns;
    const std::int64_t timeout_ns = plan.transaction_timeout.count();
    std::uint64_t measured_sends = 0;
    std::uint16_t tid = 0;
    for (;;) {
        if (setup_.options->stop && setup_.options->stop->load(std::memory_order_relaxed)) break;
        if (setup_.abort && setup_.abort->load(std::memory_order_relaxed)) break;
        std::int64_t now = net::now_ns();
        if (now >= setup_.end_ns) break;
        if (plan.transactions != 0 && measured_sends >= plan.transactions) break;
        if (now >= measure_from)
            interval_.tick(static_cast<std::uint64_t>(now - measure_from), *setup_.timeline, 0);
        const std::int64_t wait = pace(now);
        if (wait != 0) {
            // Nothing to send yet: sleep in short steps, so stops and stage changes are seen.
            const std::int64_t step = wait < 0 ? net::kNsPerMs : std::min(wait, 10 * net::kNsPerMs);
            net::sleep_until_ns(std::min(now + step, setup_.end_ns));
            continue;
        }
        std::int64_t intended = now;
        if (open_loop_) {
            intended = next_send_;
            const std::int64_t lag = now - intended;
            if (lag > plan.late_threshold.count() && now >= measure_from) {
                // The line was still busy with the previous transaction: the target's doing.
                ++target_lag.late_sends;
                target_lag.total_lag_ns += static_cast<std::uint64_t>(lag);
                target_lag.max_lag_ns =
                    std::max(target_lag.max_lag_ns, static_cast<std::uint64_t>(lag));
            }
            const double rate = setup_.schedule->empty()
                                    ? plan.rate
                                    : setup_.schedule->at(intended - measure_from).rate;
            next_send_ += static_cast<std::int64_t>(1e9 / rate);
        }
        RequestInfo info;
        const std::size_t size = generator.next(++tid, adu, info);
        if (size <= codec::limits::kMbapHeader) {
            fatal_error = Error(ErrorCode::InvalidInput, "the operation could not be encoded");
            break;
        }
        const codec::Bytes pdu(adu.data() + codec::limits::kMbapHeader,
                               size - codec::limits::kMbapHeader);
        codec::Bytes answer;
        std::int64_t sent_ns = 0;
        const SerialOutcome so = master_.transact(info.unit_id, pdu, timeout_ns, answer, sent_ns);
        const std::int64_t done = net::now_ns();
        stats::Outcome outcome = outcome_of(so);
        codec::Response rsp;
        if (so == SerialOutcome::Answered) {
            codec::TcpFrame frame;
            frame.header = {tid, 0, static_cast<std::uint16_t>(answer.size() + 1), info.unit_id};
            frame.pdu = answer;
            outcome = check_response(info, frame, rsp);
            if (outcome == stats::Outcome::Ok && setup_.options->verifier.check &&
                !setup_.options->verifier.check(setup_.options->verifier.context, info, rsp))
                outcome = stats::Outcome::ValueMismatch;
        }
        if (so == SerialOutcome::BadCheck) ++bad_checks;
        if (sent_ns >= measure_from) {
            ++measured_sends;
            if (done >= measure_from)
                interval_.tick(static_cast<std::uint64_t>(done - measure_from), *setup_.timeline,
                               0);
            // Open loop: latency from the intended send time, so a busy line is not hidden.
            const std::int64_t from = open_loop_ ? intended : sent_ns;
            const bool timed =
                so == SerialOutcome::Answered &&
                (outcome == stats::Outcome::Ok || outcome == stats::Outcome::Exception);
            if (timed && open_loop_)
                service_time.record(
                    static_cast<std::uint64_t>(std::max<std::int64_t>(done - sent_ns, 0)));
            record(info, outcome, static_cast<std::uint8_t>(rsp.exception), timed,
                   static_cast<std::uint64_t>(std::max<std::int64_t>(done - from, 0)),
                   pdu.size() + kUnitAndCheck, answer.size() + kUnitAndCheck, from);
        }
        if (so == SerialOutcome::IoError) {
            fatal_error =
                Error(ErrorCode::Io, std::strerror(master_.io_error()), plan.serial.device);
            break;
        }
    }
    finished_ns = net::now_ns();
    if (finished_ns >= measure_from) interval_.flush(*setup_.timeline, 0);
    open_.store(0, std::memory_order_relaxed);
    if (setup_.live != nullptr) setup_.live->open_connections.set(0);
}

void SerialRunner::record(const RequestInfo& info, stats::Outcome outcome, std::uint8_t exception,
                          bool timed, std::uint64_t latency_ns, std::size_t sent_bytes,
                          std::size_t received_bytes, std::int64_t from) noexcept {
    auto count = [&](stats::OutcomeCounters& c) {
        ++c.transactions_sent;
        c.bytes_sent += sent_bytes;
        c.bytes_received += received_bytes;
        if (outcome == stats::Outcome::Exception)
            c.record_exception(exception);
        else
            c.record(outcome);
    };
    stats::OperationResult& op = operations[info.op_index];
    count(counters);
    count(op.counters);
    if (timed) op.latency.record(latency_ns);
    if (!setup_.schedule->empty()) {
        stats::StageResult& stage =
            stages[setup_.schedule->stage_at(from - setup_.measure_start_ns)];
        count(stage.counters);
        if (timed) stage.latency.record(latency_ns);
        if (!stage.operations.empty()) {
            count(stage.operations[info.op_index].counters);
            if (timed) stage.operations[info.op_index].latency.record(latency_ns);
        }
    }
    if (timed) interval_.record_latency(latency_ns, info.op_index);
    interval_.record_transaction(outcome != stats::Outcome::Ok);
    if (setup_.live != nullptr) {
        LiveOperationCells& cells = setup_.live->operations[info.op_index];
        cells.sent.add();
        cells.bytes_sent.add(sent_bytes);
        cells.bytes_received.add(received_bytes);
        setup_.live->record(info.op_index, outcome, exception, timed, latency_ns);
    }
}

}  // namespace mbstorm::load
