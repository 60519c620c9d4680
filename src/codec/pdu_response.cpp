// Response PDUs (normal and exception): decode into views, encode into the caller's buffer.
#include <cstring>

#include "codec/limits.hpp"
#include "codec/pdu.hpp"
#include "codec/pdu_rules.hpp"

namespace mbstorm::codec {
namespace {

using detail::exact_size;

// Largest data block after a one-byte byte count: 125 registers or 2000 coils.
constexpr std::size_t kMaxReadDataBytes = 2u * limits::kMaxReadRegisters;
// FC0C: status, event count and message count precede the events.
constexpr std::size_t kCommLogFixedBytes = 6;

// FC01-04,17: byte count then data.
CodecError decode_read_data(const std::uint8_t* p, std::size_t n, bool registers,
                            Response& out) noexcept {
    if (n < 2) return CodecError::Truncated;
    const std::size_t byte_count = p[1];
    if (byte_count == 0 || byte_count > kMaxReadDataBytes) return CodecError::QuantityOutOfRange;
    if (registers && (byte_count & 1u) != 0) return CodecError::ByteCountMismatch;
    if (n != 2 + byte_count) return exact_size(n, 2 + byte_count);
    out.payload = Bytes(p + 2, byte_count);
    return CodecError::Ok;
}

CodecError decode_write_echo(const std::uint8_t* p, std::size_t n, std::uint16_t max_quantity,
                             Response& out) noexcept {
    if (n != 5) return exact_size(n, 5);
    out.address = load_be16(p + 1);
    out.quantity = load_be16(p + 3);
    if (static_cast<std::uint16_t>(out.quantity - 1u) >= max_quantity) {
        return CodecError::QuantityOutOfRange;
    }
    if (!detail::range_fits(out.address, out.quantity)) return CodecError::AddressOverflow;
    return CodecError::Ok;
}

CodecError decode_diagnostics(const std::uint8_t* p, std::size_t n, Response& out) noexcept {
    if (n < 3) return CodecError::Truncated;
    out.sub_function = load_be16(p + 1);
    switch (detail::diagnostic_data(out.sub_function)) {
        case detail::DiagnosticData::Unknown:
            return CodecError::UnsupportedSubFunction;
        case detail::DiagnosticData::AnyLength:
            break;
        case detail::DiagnosticData::OneWord:
            if (n != 5) return exact_size(n, 5);
            break;
    }
    out.payload = Bytes(p + 3, n - 3);
    return CodecError::Ok;
}

CodecError decode_comm_event_log(const std::uint8_t* p, std::size_t n, Response& out) noexcept {
    if (n < 2) return CodecError::Truncated;
    const std::size_t byte_count = p[1];
    if (byte_count < kCommLogFixedBytes) return CodecError::ByteCountMismatch;
    if (byte_count > kCommLogFixedBytes + limits::kMaxCommEventBytes) {
        return CodecError::QuantityOutOfRange;
    }
    if (n != 2 + byte_count) return exact_size(n, 2 + byte_count);
    out.status = load_be16(p + 2);
    out.event_count = load_be16(p + 4);
    out.message_count = load_be16(p + 6);
    out.payload = Bytes(p + 8, byte_count - kCommLogFixedBytes);
    return CodecError::Ok;
}

CodecError decode_report_server_id(const std::uint8_t* p, std::size_t n, Response& out) noexcept {
    if (n < 2) return CodecError::Truncated;
    const std::size_t byte_count = p[1];
    if (byte_count == 0) return CodecError::ByteCountMismatch;  // at least the run indicator
    if (n != 2 + byte_count) return exact_size(n, 2 + byte_count);
    out.payload = Bytes(p + 2, byte_count);
    return CodecError::Ok;
}

// FC14 response: (length, reference type, record data)*. The spec's 0x07 minimum for the
// response length contradicts its own format (one 1-register sub-response is 4 bytes), so
// only the maximum is enforced.
CodecError decode_read_file(const std::uint8_t* p, std::size_t n, Response& out) noexcept {
    if (n < 2) return CodecError::Truncated;
    const std::size_t byte_count = p[1];
    if (byte_count == 0 || byte_count > limits::kMaxFileResponseBytes) {
        return CodecError::ByteCountMismatch;
    }
    if (n != 2 + byte_count) return exact_size(n, 2 + byte_count);
    out.payload = Bytes(p + 2, byte_count);
    FileResponseIterator it(out.payload);
    FileSubResponse sub;
    CodecError e;
    while ((e = it.next(sub)) == CodecError::Ok) {
        // Record data is whole registers, at least one.
        if (sub.record_data.empty() || (sub.record_data.size() & 1u) != 0) {
            return CodecError::ByteCountMismatch;
        }
        if (sub.reference_type != limits::kFileReferenceType) {
            return CodecError::InvalidReferenceType;
        }
    }
    return e == CodecError::Empty ? CodecError::Ok : CodecError::ByteCountMismatch;
}

// FC15 response: an echo of the request.
CodecError decode_write_file(const std::uint8_t* p, std::size_t n, Response& out) noexcept {
    if (n < 2) return CodecError::Truncated;
    const std::size_t byte_count = p[1];
    if (!detail::in_range(byte_count, limits::kMinFileWriteBytes, limits::kMaxFileWriteBytes)) {
        return CodecError::ByteCountMismatch;
    }
    if (n != 2 + byte_count) return exact_size(n, 2 + byte_count);
    out.payload = Bytes(p + 2, byte_count);
    return detail::check_file_sub_requests(out.payload, true).error;
}

CodecError decode_fifo(const std::uint8_t* p, std::size_t n, Response& out) noexcept {
    if (n < 5) return CodecError::Truncated;
    const std::size_t byte_count = load_be16(p + 1);
    out.fifo_count = load_be16(p + 3);
    if (out.fifo_count > limits::kMaxFifoCount) return CodecError::QuantityOutOfRange;
    if (byte_count != 2u + 2u * out.fifo_count) return CodecError::ByteCountMismatch;
    if (n != 3 + byte_count) return exact_size(n, 3 + byte_count);
    out.payload = Bytes(p + 5, byte_count - 2u);
    return CodecError::Ok;
}

CodecError decode_device_id(const std::uint8_t* p, std::size_t n, Response& out) noexcept {
    if (n < 2) return CodecError::Truncated;
    out.mei_type = p[1];
    if (out.mei_type != kMeiReadDeviceId) return CodecError::UnsupportedSubFunction;
    constexpr std::size_t kFixed = 7;  // fc, mei, code, conformity, more, next, count
    if (n < kFixed) return CodecError::Truncated;
    out.device_id_code = p[2];
    out.conformity_level = p[3];
    out.more_follows = p[4];
    out.next_object_id = p[5];
    out.object_count = p[6];
    if (!detail::in_range(out.device_id_code, limits::kMinDeviceIdCode, limits::kMaxDeviceIdCode)) {
        return CodecError::InvalidDeviceIdCode;
    }
    out.payload = Bytes(p + kFixed, n - kFixed);
    DeviceIdObjectIterator it(out.payload);
    DeviceIdObject object;
    for (unsigned i = 0; i < out.object_count; ++i) {
        const CodecError e = it.next(object);
        if (e != CodecError::Ok) return CodecError::Truncated;
    }
    return it.next(object) == CodecError::Empty ? CodecError::Ok : CodecError::TrailingBytes;
}

EncodeResult emit(MutableBytes out, const std::uint8_t* head, std::size_t head_size,
                  Bytes payload) noexcept {
    const std::size_t total = head_size + payload.size();
    if (total > out.size()) return {0, CodecError::BufferTooSmall};
    // The payload may already sit in `out` (built in place): move it before the head lands.
    if (!payload.empty()) std::memmove(out.data() + head_size, payload.data(), payload.size());
    std::memcpy(out.data(), head, head_size);
    return {total, CodecError::Ok};
}

EncodeResult encode_raw(const Response& r, MutableBytes out) noexcept {
    constexpr EncodeResult kInvalid{0, CodecError::InvalidArgument};
    std::uint8_t h[8];
    h[0] = r.function;
    switch (static_cast<FunctionCode>(r.function)) {
        case FunctionCode::ReadCoils:
        case FunctionCode::ReadDiscreteInputs:
        case FunctionCode::ReadHoldingRegisters:
        case FunctionCode::ReadInputRegisters:
        case FunctionCode::ReportServerId:
        case FunctionCode::ReadFileRecord:
        case FunctionCode::WriteFileRecord:
        case FunctionCode::ReadWriteMultipleRegisters:
            if (r.payload.size() > 0xFF) return kInvalid;
            h[1] = static_cast<std::uint8_t>(r.payload.size());
            return emit(out, h, 2, r.payload);
        case FunctionCode::WriteSingleCoil:
        case FunctionCode::WriteSingleRegister:
            store_be16(h + 1, r.address);
            store_be16(h + 3, r.value);
            return emit(out, h, 5, {});
        case FunctionCode::ReadExceptionStatus:
            h[1] = r.exception_status;
            return emit(out, h, 2, {});
        case FunctionCode::Diagnostics:
            store_be16(h + 1, r.sub_function);
            return emit(out, h, 3, r.payload);
        case FunctionCode::GetCommEventCounter:
            store_be16(h + 1, r.status);
            store_be16(h + 3, r.event_count);
            return emit(out, h, 5, {});
        case FunctionCode::GetCommEventLog:
            if (r.payload.size() > 0xFF - kCommLogFixedBytes) return kInvalid;
            h[1] = static_cast<std::uint8_t>(kCommLogFixedBytes + r.payload.size());
            store_be16(h + 2, r.status);
            store_be16(h + 4, r.event_count);
            store_be16(h + 6, r.message_count);
            return emit(out, h, 8, r.payload);
        case FunctionCode::WriteMultipleCoils:
        case FunctionCode::WriteMultipleRegisters:
            store_be16(h + 1, r.address);
            store_be16(h + 3, r.quantity);
            return emit(out, h, 5, {});
        case FunctionCode::MaskWriteRegister:
            store_be16(h + 1, r.address);
            store_be16(h + 3, r.and_mask);
            store_be16(h + 5, r.or_mask);
            return emit(out, h, 7, {});
        case FunctionCode::ReadFifoQueue:
            if (r.fifo_count > limits::kMaxFifoCount) return kInvalid;
            store_be16(h + 1, static_cast<std::uint16_t>(2u + 2u * r.fifo_count));
            store_be16(h + 3, r.fifo_count);
            return emit(out, h, 5, r.payload);
        case FunctionCode::EncapsulatedInterface:
            if (r.mei_type != kMeiReadDeviceId) return kInvalid;
            h[1] = r.mei_type;
            h[2] = r.device_id_code;
            h[3] = r.conformity_level;
            h[4] = r.more_follows;
            h[5] = r.next_object_id;
            h[6] = r.object_count;
            return emit(out, h, 7, r.payload);
    }
    return kInvalid;
}

}  // namespace

CodecError decode_response(Bytes pdu, Response& out) noexcept {
    out = Response{};
    const std::size_t n = pdu.size();
    if (n == 0) return CodecError::Empty;
    const std::uint8_t* p = pdu.data();
    const std::uint8_t fc = p[0];
    out.function = fc & 0x7Fu;
    if ((fc & kExceptionBit) != 0) {
        // Any function may be refused (01 is the answer to an unknown one), so no FC check.
        if (n != 2) return exact_size(n, 2);
        if (p[1] == 0) return CodecError::InvalidExceptionCode;
        out.exception = static_cast<ExceptionCode>(p[1]);
        return CodecError::Ok;
    }
    if (n > limits::kMaxPdu) return CodecError::TrailingBytes;
    switch (static_cast<FunctionCode>(fc)) {
        case FunctionCode::ReadCoils:
        case FunctionCode::ReadDiscreteInputs:
            return decode_read_data(p, n, false, out);
        case FunctionCode::ReadHoldingRegisters:
        case FunctionCode::ReadInputRegisters:
        case FunctionCode::ReadWriteMultipleRegisters:
            return decode_read_data(p, n, true, out);
        case FunctionCode::WriteSingleCoil:
        case FunctionCode::WriteSingleRegister:
            if (n != 5) return exact_size(n, 5);
            out.address = load_be16(p + 1);
            out.value = load_be16(p + 3);
            if (fc == to_byte(FunctionCode::WriteSingleCoil) && out.value != limits::kCoilOn &&
                out.value != limits::kCoilOff) {
                return CodecError::InvalidCoilValue;
            }
            return CodecError::Ok;
        case FunctionCode::ReadExceptionStatus:
            if (n != 2) return exact_size(n, 2);
            out.exception_status = p[1];
            return CodecError::Ok;
        case FunctionCode::Diagnostics:
            return decode_diagnostics(p, n, out);
        case FunctionCode::GetCommEventCounter:
            if (n != 5) return exact_size(n, 5);
            out.status = load_be16(p + 1);
            out.event_count = load_be16(p + 3);
            return CodecError::Ok;
        case FunctionCode::GetCommEventLog:
            return decode_comm_event_log(p, n, out);
        case FunctionCode::WriteMultipleCoils:
            return decode_write_echo(p, n, limits::kMaxWriteCoils, out);
        case FunctionCode::WriteMultipleRegisters:
            return decode_write_echo(p, n, limits::kMaxWriteRegisters, out);
        case FunctionCode::ReportServerId:
            return decode_report_server_id(p, n, out);
        case FunctionCode::ReadFileRecord:
            return decode_read_file(p, n, out);
        case FunctionCode::WriteFileRecord:
            return decode_write_file(p, n, out);
        case FunctionCode::MaskWriteRegister:
            if (n != 7) return exact_size(n, 7);
            out.address = load_be16(p + 1);
            out.and_mask = load_be16(p + 3);
            out.or_mask = load_be16(p + 5);
            return CodecError::Ok;
        case FunctionCode::ReadFifoQueue:
            return decode_fifo(p, n, out);
        case FunctionCode::EncapsulatedInterface:
            return decode_device_id(p, n, out);
    }
    return CodecError::UnsupportedFunction;
}

EncodeResult encode_response(const Response& rsp, MutableBytes out) noexcept {
    if (rsp.exception != ExceptionCode::None) {
        return encode_exception(rsp.function, rsp.exception, out);
    }
    const EncodeResult written = encode_raw(rsp, out);
    if (!written.ok()) return written;
    // One place per fact: the decoder's checks are the encoder's checks.
    Response check;
    if (decode_response(Bytes(out.data(), written.size), check) != CodecError::Ok) {
        return {0, CodecError::InvalidArgument};
    }
    return written;
}

EncodeResult encode_exception(std::uint8_t function, ExceptionCode code,
                              MutableBytes out) noexcept {
    if (code == ExceptionCode::None || (function & kExceptionBit) != 0) {
        return {0, CodecError::InvalidArgument};
    }
    if (out.size() < 2) return {0, CodecError::BufferTooSmall};
    out[0] = static_cast<std::uint8_t>(function | kExceptionBit);
    out[1] = static_cast<std::uint8_t>(code);
    return {2, CodecError::Ok};
}

}  // namespace mbstorm::codec
