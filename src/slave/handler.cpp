#include "slave/handler.hpp"

#include <cstring>

#include "codec/function_code.hpp"
#include "codec/limits.hpp"
#include "codec/pdu.hpp"

namespace mbstorm::slave {

namespace {

using codec::ExceptionCode;
using codec::FunctionCode;
namespace limits = codec::limits;

// The hot paths are inlined into one function so the result stays in registers: returning the
// small HandleResult through several calls made GCC assemble it on the stack byte by byte and
// stall store forwarding (about half the time of an FC03 x10 request).
#define MBSTORM_HOT [[gnu::always_inline]] inline

constexpr std::uint8_t kReceiveBroadcastEvent = 0xC0;

MBSTORM_HOT HandleResult answer(std::uint8_t function, std::size_t size,
                                bool wrote = false) noexcept {
    // One aggregate initialisation: built in a register, not field by field on the stack
    // (byte stores followed by a wide load stall store forwarding on the hot path).
    return HandleResult{static_cast<std::uint32_t>(size), Outcome::Response, ExceptionCode::None,
                        function, wrote};
}

MBSTORM_HOT HandleResult fail(std::uint8_t function, ExceptionCode code,
                              std::uint8_t* out) noexcept {
    out[0] = static_cast<std::uint8_t>(function | codec::kExceptionBit);
    out[1] = static_cast<std::uint8_t>(code);
    return HandleResult{2, Outcome::Exception, code, function, false};
}

// Echoes the first `n` request bytes (the request is never longer than a PDU).
MBSTORM_HOT HandleResult echo(codec::Bytes request, std::size_t n, std::uint8_t* out,
                              bool wrote) noexcept {
    std::memcpy(out, request.data(), n);
    return answer(request[0], n, wrote);
}

// The spec's send-event bits for the FC0C event log.
std::uint8_t send_event(const HandleResult& r) noexcept {
    if (r.outcome != Outcome::Exception) return kSendEvent;
    switch (r.exception) {
        case ExceptionCode::IllegalFunction:
        case ExceptionCode::IllegalDataAddress:
        case ExceptionCode::IllegalDataValue:
            return kSendEvent | 0x01;
        case ExceptionCode::ServerDeviceFailure:
            return kSendEvent | 0x02;
        case ExceptionCode::Acknowledge:
        case ExceptionCode::ServerDeviceBusy:
            return kSendEvent | 0x04;
        default:
            return kSendEvent;
    }
}

// ---- bit and register tables ----

MBSTORM_HOT HandleResult read_bits(const codec::Request& req, const BitTable& table,
                                   std::uint8_t* out) noexcept {
    if (!table.contains(req.address, req.quantity)) {
        return fail(req.function, ExceptionCode::IllegalDataAddress, out);
    }
    const std::size_t bytes = (std::size_t{req.quantity} + 7) / 8;
    out[0] = req.function;
    out[1] = static_cast<std::uint8_t>(bytes);
    table.read_packed(req.address, req.quantity, out + 2);
    return answer(req.function, 2 + bytes);
}

MBSTORM_HOT HandleResult read_registers(const codec::Request& req, RegisterTable& table,
                                        std::uint8_t* out) noexcept {
    if (!table.contains(req.address, req.quantity)) {
        return fail(req.function, ExceptionCode::IllegalDataAddress, out);
    }
    out[0] = req.function;
    out[1] = static_cast<std::uint8_t>(2 * req.quantity);
    table.read_be(req.address, req.quantity, out + 2);
    return answer(req.function, 2 + 2 * std::size_t{req.quantity});
}

MBSTORM_HOT HandleResult write_single_coil(const codec::Request& req, codec::Bytes request,
                                           DataModel& m, std::uint8_t* out) noexcept {
    // The codec already answered 03 for values other than 0x0000 / 0xFF00.
    if (!m.coils().contains(req.address, 1)) {
        return fail(req.function, ExceptionCode::IllegalDataAddress, out);
    }
    m.coils().set(req.address, req.value == limits::kCoilOn);
    return echo(request, 5, out, true);
}

MBSTORM_HOT HandleResult write_single_register(const codec::Request& req, codec::Bytes request,
                                               DataModel& m, std::uint8_t* out) noexcept {
    if (!m.holding_registers().contains(req.address, 1)) {
        return fail(req.function, ExceptionCode::IllegalDataAddress, out);
    }
    m.holding_registers().set(req.address, req.value);
    return echo(request, 5, out, true);
}

MBSTORM_HOT HandleResult write_multiple_coils(const codec::Request& req, codec::Bytes request,
                                              DataModel& m, std::uint8_t* out) noexcept {
    if (!m.coils().contains(req.address, req.quantity)) {
        return fail(req.function, ExceptionCode::IllegalDataAddress, out);
    }
    m.coils().write_packed(req.address, req.quantity, req.payload.data());
    return echo(request, 5, out, true);  // function, address, quantity
}

MBSTORM_HOT HandleResult write_multiple_registers(const codec::Request& req, codec::Bytes request,
                                                  DataModel& m, std::uint8_t* out) noexcept {
    if (!m.holding_registers().contains(req.address, req.quantity)) {
        return fail(req.function, ExceptionCode::IllegalDataAddress, out);
    }
    m.holding_registers().write_be(req.address, req.quantity, req.payload.data());
    return echo(request, 5, out, true);
}

HandleResult mask_write_register(const codec::Request& req, codec::Bytes request, DataModel& m,
                                 std::uint8_t* out) noexcept {
    if (!m.holding_registers().contains(req.address, 1)) {
        return fail(req.function, ExceptionCode::IllegalDataAddress, out);
    }
    m.holding_registers().mask_write(req.address, req.and_mask, req.or_mask);
    return echo(request, 7, out, true);
}

// FC17: the write happens before the read, so overlapping ranges read the new values.
HandleResult read_write_registers(const codec::Request& req, DataModel& m,
                                  std::uint8_t* out) noexcept {
    RegisterTable& regs = m.holding_registers();
    if (!regs.contains(req.address, req.quantity) ||
        !regs.contains(req.write_address, req.write_quantity)) {
        return fail(req.function, ExceptionCode::IllegalDataAddress, out);
    }
    regs.write_be(req.write_address, req.write_quantity, req.payload.data());
    out[0] = req.function;
    out[1] = static_cast<std::uint8_t>(2 * req.quantity);
    regs.read_be(req.address, req.quantity, out + 2);
    return answer(req.function, 2 + 2 * std::size_t{req.quantity}, true);
}

// FC18: count register at the pointer, values after it (see DataModel).
HandleResult read_fifo(const codec::Request& req, DataModel& m, std::uint8_t* out) noexcept {
    RegisterTable& regs = m.holding_registers();
    if (!regs.contains(req.address, 1)) {
        return fail(req.function, ExceptionCode::IllegalDataAddress, out);
    }
    const std::uint16_t count = regs.get(req.address);
    if (count > limits::kMaxFifoCount) {
        return fail(req.function, ExceptionCode::IllegalDataValue, out);
    }
    if (!regs.contains(req.address, 1 + std::uint32_t{count})) {
        return fail(req.function, ExceptionCode::IllegalDataAddress, out);
    }
    out[0] = req.function;
    codec::store_be16(out + 1, static_cast<std::uint16_t>(2 + 2 * count));
    codec::store_be16(out + 3, count);
    regs.read_be(static_cast<std::uint16_t>(req.address + 1), count, out + 5);
    return answer(req.function, 5 + 2 * std::size_t{count});
}

// ---- file records ----

// Validates every sub-request before touching anything, so a bad one changes nothing.
// 03 (malformed, response too long) outranks 02 (unknown file, record range, reference type).
ExceptionCode check_file_request(codec::Bytes sub_requests, bool with_data, const FileStore& files,
                                 std::size_t& response_bytes) noexcept {
    codec::FileRecordIterator it(sub_requests, with_data);
    codec::FileSubRequest sub;
    bool bad_address = false;
    response_bytes = 0;
    for (;;) {
        const codec::CodecError e = it.next(sub);
        if (e == codec::CodecError::Empty) break;
        if (e != codec::CodecError::Ok) return ExceptionCode::IllegalDataValue;
        response_bytes += 2 + 2 * std::size_t{sub.record_length};
        if (sub.reference_type != limits::kFileReferenceType ||
            !files.contains(sub.file_number, sub.record_number, sub.record_length)) {
            bad_address = true;
        }
    }
    // FC14 response: function + byte count + sub-responses must fit one PDU.
    if (!with_data && 2 + response_bytes > limits::kMaxPdu) return ExceptionCode::IllegalDataValue;
    return bad_address ? ExceptionCode::IllegalDataAddress : ExceptionCode::None;
}

HandleResult read_file_record(const codec::Request& req, DataModel& m, std::uint8_t* out) noexcept {
    std::size_t data_bytes = 0;
    const ExceptionCode e = check_file_request(req.payload, false, m.files(), data_bytes);
    if (e != ExceptionCode::None) return fail(req.function, e, out);
    out[0] = req.function;
    out[1] = static_cast<std::uint8_t>(data_bytes);
    std::uint8_t* p = out + 2;
    codec::FileRecordIterator it(req.payload, false);
    codec::FileSubRequest sub;
    while (it.next(sub) == codec::CodecError::Ok) {
        p[0] = static_cast<std::uint8_t>(1 + 2 * sub.record_length);
        p[1] = limits::kFileReferenceType;
        m.files().read_be(sub.file_number, sub.record_number, sub.record_length, p + 2);
        p += 2 + 2 * std::size_t{sub.record_length};
    }
    return answer(req.function, static_cast<std::size_t>(p - out));
}

HandleResult write_file_record(const codec::Request& req, codec::Bytes request, DataModel& m,
                               std::uint8_t* out) noexcept {
    std::size_t unused = 0;
    const ExceptionCode e = check_file_request(req.payload, true, m.files(), unused);
    if (e != ExceptionCode::None) return fail(req.function, e, out);
    codec::FileRecordIterator it(req.payload, true);
    codec::FileSubRequest sub;
    while (it.next(sub) == codec::CodecError::Ok) {
        m.files().write_be(sub.file_number, sub.record_number, sub.record_length,
                           sub.record_data.data());
    }
    return echo(request, request.size(), out, true);
}

// ---- diagnostics and identification ----

HandleResult diagnostics(const codec::Request& req, codec::Bytes request, DataModel& m,
                         std::uint8_t* out) noexcept {
    using Sub = codec::DiagnosticSubFunction;
    const auto sub = static_cast<Sub>(req.sub_function);
    if (sub == Sub::ReturnQueryData) return echo(request, request.size(), out, false);

    Diagnostics& d = m.diagnostics();
    const bool known = sub == Sub::RestartCommunications || sub == Sub::ReturnDiagnosticRegister ||
                       (req.sub_function >= 0x0A && req.sub_function <= 0x12) ||
                       sub == Sub::ClearOverrunCounterAndFlag;
    if (!known) return fail(req.function, ExceptionCode::IllegalFunction, out);
    if (req.payload.size() != 2) return fail(req.function, ExceptionCode::IllegalDataValue, out);
    const std::uint16_t data = codec::load_be16(req.payload.data());

    if (sub == Sub::RestartCommunications) {
        if (data != 0x0000 && data != 0xFF00) {
            return fail(req.function, ExceptionCode::IllegalDataValue, out);
        }
        d.clear_counters();
        if (data == 0xFF00) d.clear_event_log();
        return echo(request, request.size(), out, true);
    }
    if (data != 0) return fail(req.function, ExceptionCode::IllegalDataValue, out);

    std::uint16_t value = 0;
    switch (sub) {
        case Sub::ClearCounters:
            d.clear_counters();
            return echo(request, request.size(), out, true);
        case Sub::ClearOverrunCounterAndFlag:  // overruns cannot happen over TCP
            return echo(request, request.size(), out, false);
        case Sub::ReturnDiagnosticRegister:
            value = 0;
            break;
        case Sub::ReturnBusMessageCount:
        case Sub::ReturnServerMessageCount:
            value = d.message_count();
            break;
        case Sub::ReturnBusCommunicationErrorCount:
            value = d.comm_error_count();
            break;
        case Sub::ReturnBusExceptionErrorCount:
            value = d.exception_count();
            break;
        case Sub::ReturnServerNoResponseCount:
            value = d.no_response_count();
            break;
        case Sub::ReturnServerBusyCount:
            value = d.busy_count();
            break;
        default:
            value = 0;
            break;  // NAK, character overrun: never happen here
    }
    out[0] = req.function;
    codec::store_be16(out + 1, req.sub_function);
    codec::store_be16(out + 3, value);
    return answer(req.function, 5);
}

HandleResult comm_event_counter(const codec::Request& req, DataModel& m,
                                std::uint8_t* out) noexcept {
    Diagnostics& d = m.diagnostics();
    if (m.track_diagnostics()) d.note_fetch();
    out[0] = req.function;
    codec::store_be16(out + 1, 0x0000);  // status: never busy with a previous command
    codec::store_be16(out + 3, d.comm_event_count());
    return answer(req.function, 5);
}

HandleResult comm_event_log(const codec::Request& req, DataModel& m, std::uint64_t seq,
                            std::uint8_t* out) noexcept {
    Diagnostics& d = m.diagnostics();
    std::size_t events = 0;
    if (m.track_diagnostics()) {
        d.note_fetch();
        events = d.read_event_log(seq, out + 8);
    }
    out[0] = req.function;
    out[1] = static_cast<std::uint8_t>(6 + events);
    codec::store_be16(out + 2, 0x0000);
    codec::store_be16(out + 4, d.comm_event_count());
    codec::store_be16(out + 6, d.message_count());
    return answer(req.function, 8 + events);
}

HandleResult report_server_id(const codec::Request& req, DataModel& m, std::uint8_t* out) noexcept {
    const auto id = m.server_id();  // at most 250 bytes (checked when the model was built)
    out[0] = req.function;
    out[1] = static_cast<std::uint8_t>(id.size() + 1);
    if (!id.empty()) std::memcpy(out + 2, id.data(), id.size());
    out[2 + id.size()] = m.run_indicator_on() ? 0xFF : 0x00;
    return answer(req.function, 3 + id.size());
}

HandleResult read_device_id(const codec::Request& req, DataModel& m, std::uint8_t* out) noexcept {
    if (req.mei_type != codec::kMeiReadDeviceId) {
        return fail(req.function, ExceptionCode::IllegalFunction, out);
    }
    const DeviceIdentity& ident = m.identity();
    const std::uint8_t code = req.device_id_code;
    std::uint8_t more_follows = 0x00, next_object = 0x00, count = 0;
    std::size_t pos = 7;
    auto put = [&](unsigned id) {
        const std::string& v = ident.get(static_cast<std::uint8_t>(id));
        out[pos] = static_cast<std::uint8_t>(id);
        out[pos + 1] = static_cast<std::uint8_t>(v.size());
        std::memcpy(out + pos + 2, v.data(), v.size());
        pos += 2 + v.size();
        ++count;
    };
    if (code == 4) {
        // Individual access: an unknown object is an address error.
        if (!ident.present(req.object_id)) {
            return fail(req.function, ExceptionCode::IllegalDataAddress, out);
        }
        put(req.object_id);
    } else {
        // Stream access: 1 basic 0x00-0x02, 2 regular up to 0x06, 3 extended up to 0xFF.
        // An object id outside the category, or unknown, restarts at object 0.
        const unsigned last = code == 1 ? 0x02 : code == 2 ? 0x06 : 0xFF;
        unsigned first = req.object_id;
        if (first > last || !ident.present(req.object_id)) first = 0;
        for (unsigned id = first; id <= last; ++id) {
            if (!ident.present(static_cast<std::uint8_t>(id))) continue;
            if (pos + 2 + ident.get(static_cast<std::uint8_t>(id)).size() > limits::kMaxPdu) {
                more_follows = 0xFF;
                next_object = static_cast<std::uint8_t>(id);
                break;
            }
            put(id);
        }
    }
    out[0] = req.function;
    out[1] = codec::kMeiReadDeviceId;
    out[2] = code;
    out[3] = ident.conformity_level();
    out[4] = more_follows;
    out[5] = next_object;
    out[6] = count;
    return answer(req.function, pos);
}

MBSTORM_HOT HandleResult dispatch(codec::Bytes request, DataModel& m, std::uint64_t seq,
                                  std::uint8_t* out) noexcept {
    codec::Request req;
    const codec::RequestStatus status = codec::decode_request(request, req);
    const std::uint8_t function = request[0];
    if (!status.ok()) {
        // The codec knows the precedence (01 before 03 before its own 02 wrap check).
        const ExceptionCode code = status.exception == ExceptionCode::None
                                       ? ExceptionCode::IllegalDataValue
                                       : status.exception;
        return fail(function, code, out);
    }
    switch (static_cast<FunctionCode>(function)) {
        case FunctionCode::ReadCoils:
            return read_bits(req, m.coils(), out);
        case FunctionCode::ReadDiscreteInputs:
            return read_bits(req, m.discrete_inputs(), out);
        case FunctionCode::ReadHoldingRegisters:
            return read_registers(req, m.holding_registers(), out);
        case FunctionCode::ReadInputRegisters:
            return read_registers(req, m.input_registers(), out);
        case FunctionCode::WriteSingleCoil:
            return write_single_coil(req, request, m, out);
        case FunctionCode::WriteSingleRegister:
            return write_single_register(req, request, m, out);
        case FunctionCode::ReadExceptionStatus:
            out[0] = function;
            out[1] = m.exception_status();
            return answer(function, 2);
        case FunctionCode::Diagnostics:
            return diagnostics(req, request, m, out);
        case FunctionCode::GetCommEventCounter:
            return comm_event_counter(req, m, out);
        case FunctionCode::GetCommEventLog:
            return comm_event_log(req, m, seq, out);
        case FunctionCode::WriteMultipleCoils:
            return write_multiple_coils(req, request, m, out);
        case FunctionCode::WriteMultipleRegisters:
            return write_multiple_registers(req, request, m, out);
        case FunctionCode::ReportServerId:
            return report_server_id(req, m, out);
        case FunctionCode::ReadFileRecord:
            return read_file_record(req, m, out);
        case FunctionCode::WriteFileRecord:
            return write_file_record(req, request, m, out);
        case FunctionCode::MaskWriteRegister:
            return mask_write_register(req, request, m, out);
        case FunctionCode::ReadWriteMultipleRegisters:
            return read_write_registers(req, m, out);
        case FunctionCode::ReadFifoQueue:
            return read_fifo(req, m, out);
        case FunctionCode::EncapsulatedInterface:
            return read_device_id(req, m, out);
    }
    return fail(function, ExceptionCode::IllegalFunction, out);
}

HandleResult handle_one(codec::Bytes request, DataModel& model, std::uint8_t* out,
                        bool broadcast) noexcept {
    if (!model.track_diagnostics()) return dispatch(request, model, 0, out);
    Diagnostics& d = model.diagnostics();
    const std::uint64_t seq = d.begin_message();
    HandleResult r = dispatch(request, model, seq, out);
    if (r.outcome == Outcome::Exception) d.note_exception();
    if (broadcast) {
        d.note_no_response();
        d.end_message(seq, kReceiveBroadcastEvent, 0);  // 0: no send event
    } else {
        d.end_message(seq, kReceiveEvent, send_event(r));
    }
    return r;
}

}  // namespace

HandleResult handle_request(codec::Bytes request, DataModel& model,
                            codec::MutableBytes out) noexcept {
    if (out.size() < kMinOutput || request.empty()) return HandleResult{};
    HandleResult r;
    if (read_registers_inline(request, model, out.data(), r)) return r;
    return handle_one(request, model, out.data(), false);
}

HandleResult handle_request(std::uint8_t unit_id, codec::Bytes request, const UnitModels& units,
                            codec::MutableBytes out) noexcept {
    if (out.size() < kMinOutput || request.empty()) return HandleResult{};
    if (unit_id == 0 && units.broadcast_unit_zero) {
        // Serial-line broadcast: writes run on every model, nothing is ever answered.
        HandleResult r;
        r.function = request[0];
        const bool is_write = codec::is_write_function(request[0]);
        for (std::size_t i = 0; i < units.model_count(); ++i) {
            DataModel& m = units.model_at(i);
            if (is_write) {
                r.wrote |= handle_one(request, m, out.data(), true).wrote;
            } else if (m.track_diagnostics()) {
                m.diagnostics().note_no_response();
            }
        }
        return r;
    }
    DataModel* model = units.find(unit_id);
    if (model != nullptr) {
        HandleResult r;
        if (read_registers_inline(request, *model, out.data(), r)) return r;
        return handle_one(request, *model, out.data(), false);
    }
    switch (units.unknown_unit_policy) {
        case UnknownUnitPolicy::GatewayTargetFailed:
            return fail(request[0], ExceptionCode::GatewayTargetFailedToRespond, out.data());
        case UnknownUnitPolicy::GatewayPathUnavailable:
            return fail(request[0], ExceptionCode::GatewayPathUnavailable, out.data());
        case UnknownUnitPolicy::Ignore:
            break;
    }
    HandleResult r;
    r.function = request[0];
    return r;
}

}  // namespace mbstorm::slave
