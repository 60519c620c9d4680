// Request PDUs: decode with the exception a conforming server owes, encode into the caller's
// buffer. Exception precedence follows the spec's state diagrams: 01, then 03, then 02.
#include <cstring>

#include "codec/limits.hpp"
#include "codec/pdu.hpp"
#include "codec/pdu_rules.hpp"

namespace mbstorm::codec {
namespace {

using detail::exact_size;
using detail::range_fits;

constexpr RequestStatus bad_value(CodecError e) noexcept {
    return {e, ExceptionCode::IllegalDataValue};
}
constexpr RequestStatus bad_address() noexcept {
    return {CodecError::AddressOverflow, ExceptionCode::IllegalDataAddress};
}
constexpr RequestStatus bad_function(CodecError e) noexcept {
    return {e, ExceptionCode::IllegalFunction};
}
constexpr RequestStatus size_status(std::size_t have, std::size_t want) noexcept {
    const CodecError e = exact_size(have, want);
    return e == CodecError::Ok ? RequestStatus{} : bad_value(e);
}

// FC01-04: address, quantity.
RequestStatus decode_read(const std::uint8_t* p, std::size_t n, std::uint16_t max_quantity,
                          Request& out) noexcept {
    if (n != 5) return bad_value(exact_size(n, 5));
    out.address = load_be16(p + 1);
    out.quantity = load_be16(p + 3);
    if (static_cast<std::uint16_t>(out.quantity - 1u) >= max_quantity) {
        return bad_value(CodecError::QuantityOutOfRange);
    }
    if (!range_fits(out.address, out.quantity)) return bad_address();
    return {};
}

// FC0F and FC10: address, quantity, byte count, values.
RequestStatus decode_write_multiple(const std::uint8_t* p, std::size_t n,
                                    std::uint16_t max_quantity, bool coils, Request& out) noexcept {
    if (n < 6) return bad_value(CodecError::Truncated);
    out.address = load_be16(p + 1);
    out.quantity = load_be16(p + 3);
    const std::size_t byte_count = p[5];
    if (static_cast<std::uint16_t>(out.quantity - 1u) >= max_quantity) {
        return bad_value(CodecError::QuantityOutOfRange);
    }
    const std::size_t expected =
        coils ? detail::packed_coil_bytes(out.quantity) : 2u * std::size_t{out.quantity};
    if (byte_count != expected) return bad_value(CodecError::ByteCountMismatch);
    if (n != 6 + byte_count) return bad_value(exact_size(n, 6 + byte_count));
    out.payload = Bytes(p + 6, byte_count);
    if (!range_fits(out.address, out.quantity)) return bad_address();
    return {};
}

RequestStatus decode_diagnostics(const std::uint8_t* p, std::size_t n, Request& out) noexcept {
    if (n < 3) return bad_value(CodecError::Truncated);
    out.sub_function = load_be16(p + 1);
    switch (detail::diagnostic_data(out.sub_function)) {
        case detail::DiagnosticData::Unknown:
            return bad_function(CodecError::UnsupportedSubFunction);
        case detail::DiagnosticData::AnyLength:
            if (n > limits::kMaxPdu) return bad_value(CodecError::TrailingBytes);
            break;
        case detail::DiagnosticData::OneWord:
            if (n != 5) return bad_value(exact_size(n, 5));
            break;
    }
    out.payload = Bytes(p + 3, n - 3);
    return {};
}

// FC14 and FC15: byte count, then sub-requests.
RequestStatus decode_file_request(const std::uint8_t* p, std::size_t n, bool write,
                                  Request& out) noexcept {
    if (n < 2) return bad_value(CodecError::Truncated);
    const std::size_t byte_count = p[1];
    const bool count_ok =
        write ? detail::in_range(byte_count, limits::kMinFileWriteBytes, limits::kMaxFileWriteBytes)
              : detail::in_range(byte_count, limits::kMinFileRequestBytes,
                                 limits::kMaxFileRequestBytes);
    if (!count_ok) return bad_value(CodecError::ByteCountMismatch);
    if (n != 2 + byte_count) return bad_value(exact_size(n, 2 + byte_count));
    out.payload = Bytes(p + 2, byte_count);
    const detail::FileCheck check = detail::check_file_sub_requests(out.payload, write);
    return {check.error, check.exception};
}

RequestStatus decode_mei(const std::uint8_t* p, std::size_t n, Request& out) noexcept {
    if (n < 2) return bad_value(CodecError::Truncated);
    out.mei_type = p[1];
    if (out.mei_type != kMeiReadDeviceId) return bad_function(CodecError::UnsupportedSubFunction);
    if (n != 4) return bad_value(exact_size(n, 4));
    out.device_id_code = p[2];
    out.object_id = p[3];
    // Whether the object id exists is the server's business (02 for code 4, restart otherwise).
    if (!detail::in_range(out.device_id_code, limits::kMinDeviceIdCode, limits::kMaxDeviceIdCode)) {
        return bad_value(CodecError::InvalidDeviceIdCode);
    }
    return {};
}

// Writes `head` then `payload` (which may overlap `out`: it is moved before the head lands).
EncodeResult emit(MutableBytes out, const std::uint8_t* head, std::size_t head_size,
                  Bytes payload) noexcept {
    const std::size_t total = head_size + payload.size();
    if (total > out.size()) return {0, CodecError::BufferTooSmall};
    if (!payload.empty()) std::memmove(out.data() + head_size, payload.data(), payload.size());
    std::memcpy(out.data(), head, head_size);
    return {total, CodecError::Ok};
}

EncodeResult encode_raw(const Request& r, MutableBytes out) noexcept {
    std::uint8_t h[10];
    h[0] = r.function;
    switch (static_cast<FunctionCode>(r.function)) {
        case FunctionCode::ReadCoils:
        case FunctionCode::ReadDiscreteInputs:
        case FunctionCode::ReadHoldingRegisters:
        case FunctionCode::ReadInputRegisters:
            store_be16(h + 1, r.address);
            store_be16(h + 3, r.quantity);
            return emit(out, h, 5, {});
        case FunctionCode::WriteSingleCoil:
        case FunctionCode::WriteSingleRegister:
            store_be16(h + 1, r.address);
            store_be16(h + 3, r.value);
            return emit(out, h, 5, {});
        case FunctionCode::ReadExceptionStatus:
        case FunctionCode::GetCommEventCounter:
        case FunctionCode::GetCommEventLog:
        case FunctionCode::ReportServerId:
            return emit(out, h, 1, {});
        case FunctionCode::Diagnostics:
            store_be16(h + 1, r.sub_function);
            return emit(out, h, 3, r.payload);
        case FunctionCode::WriteMultipleCoils:
        case FunctionCode::WriteMultipleRegisters:
            if (r.payload.size() > 0xFF) return {0, CodecError::InvalidArgument};
            store_be16(h + 1, r.address);
            store_be16(h + 3, r.quantity);
            h[5] = static_cast<std::uint8_t>(r.payload.size());
            return emit(out, h, 6, r.payload);
        case FunctionCode::ReadFileRecord:
        case FunctionCode::WriteFileRecord:
            if (r.payload.size() > 0xFF) return {0, CodecError::InvalidArgument};
            h[1] = static_cast<std::uint8_t>(r.payload.size());
            return emit(out, h, 2, r.payload);
        case FunctionCode::MaskWriteRegister:
            store_be16(h + 1, r.address);
            store_be16(h + 3, r.and_mask);
            store_be16(h + 5, r.or_mask);
            return emit(out, h, 7, {});
        case FunctionCode::ReadWriteMultipleRegisters:
            if (r.payload.size() > 0xFF) return {0, CodecError::InvalidArgument};
            store_be16(h + 1, r.address);
            store_be16(h + 3, r.quantity);
            store_be16(h + 5, r.write_address);
            store_be16(h + 7, r.write_quantity);
            h[9] = static_cast<std::uint8_t>(r.payload.size());
            return emit(out, h, 10, r.payload);
        case FunctionCode::ReadFifoQueue:
            store_be16(h + 1, r.address);
            return emit(out, h, 3, {});
        case FunctionCode::EncapsulatedInterface:
            h[1] = r.mei_type;
            if (r.mei_type == kMeiReadDeviceId) {
                h[2] = r.device_id_code;
                h[3] = r.object_id;
                return emit(out, h, 4, {});
            }
            return emit(out, h, 2, r.payload);  // other MEI types: opaque bytes (fuzzing)
    }
    return emit(out, h, 1, r.payload);  // unknown function: opaque bytes (fuzzing)
}

}  // namespace

RequestStatus decode_request(Bytes pdu, Request& out) noexcept {
    out = Request{};
    const std::size_t n = pdu.size();
    // The hot path of every server: a well-sized read request skips the dispatch.
    if (n == 5 && static_cast<unsigned>(pdu[0] - 1u) < 4u) {
        const std::uint8_t* p = pdu.data();
        out.function = p[0];
        out.address = load_be16(p + 1);
        out.quantity = load_be16(p + 3);
        const std::uint16_t max = p[0] <= 0x02 ? limits::kMaxReadBits : limits::kMaxReadRegisters;
        if (static_cast<std::uint16_t>(out.quantity - 1u) >= max) {
            return bad_value(CodecError::QuantityOutOfRange);
        }
        if (!range_fits(out.address, out.quantity)) return bad_address();
        return {};
    }
    if (n == 0) return {CodecError::Empty, ExceptionCode::None};  // nothing to answer to
    const std::uint8_t* p = pdu.data();
    out.function = p[0];
    switch (static_cast<FunctionCode>(p[0])) {
        case FunctionCode::ReadCoils:
        case FunctionCode::ReadDiscreteInputs:
            return decode_read(p, n, limits::kMaxReadBits, out);
        case FunctionCode::ReadHoldingRegisters:
        case FunctionCode::ReadInputRegisters:
            return decode_read(p, n, limits::kMaxReadRegisters, out);
        case FunctionCode::WriteSingleCoil:
            if (n != 5) return bad_value(exact_size(n, 5));
            out.address = load_be16(p + 1);
            out.value = load_be16(p + 3);
            if (out.value != limits::kCoilOn && out.value != limits::kCoilOff) {
                return bad_value(CodecError::InvalidCoilValue);
            }
            return {};
        case FunctionCode::WriteSingleRegister:
            if (n != 5) return bad_value(exact_size(n, 5));
            out.address = load_be16(p + 1);
            out.value = load_be16(p + 3);
            return {};
        case FunctionCode::ReadExceptionStatus:
        case FunctionCode::GetCommEventCounter:
        case FunctionCode::GetCommEventLog:
        case FunctionCode::ReportServerId:
            return size_status(n, 1);
        case FunctionCode::Diagnostics:
            return decode_diagnostics(p, n, out);
        case FunctionCode::WriteMultipleCoils:
            return decode_write_multiple(p, n, limits::kMaxWriteCoils, true, out);
        case FunctionCode::WriteMultipleRegisters:
            return decode_write_multiple(p, n, limits::kMaxWriteRegisters, false, out);
        case FunctionCode::ReadFileRecord:
            return decode_file_request(p, n, false, out);
        case FunctionCode::WriteFileRecord:
            return decode_file_request(p, n, true, out);
        case FunctionCode::MaskWriteRegister:
            if (n != 7) return bad_value(exact_size(n, 7));
            out.address = load_be16(p + 1);
            out.and_mask = load_be16(p + 3);
            out.or_mask = load_be16(p + 5);
            return {};
        case FunctionCode::ReadWriteMultipleRegisters: {
            if (n < 10) return bad_value(CodecError::Truncated);
            out.address = load_be16(p + 1);
            out.quantity = load_be16(p + 3);
            out.write_address = load_be16(p + 5);
            out.write_quantity = load_be16(p + 7);
            const std::size_t byte_count = p[9];
            if (static_cast<std::uint16_t>(out.quantity - 1u) >= limits::kMaxRwReadRegisters ||
                static_cast<std::uint16_t>(out.write_quantity - 1u) >=
                    limits::kMaxRwWriteRegisters) {
                return bad_value(CodecError::QuantityOutOfRange);
            }
            if (byte_count != 2u * out.write_quantity) {
                return bad_value(CodecError::ByteCountMismatch);
            }
            if (n != 10 + byte_count) return bad_value(exact_size(n, 10 + byte_count));
            out.payload = Bytes(p + 10, byte_count);
            if (!range_fits(out.address, out.quantity) ||
                !range_fits(out.write_address, out.write_quantity)) {
                return bad_address();
            }
            return {};
        }
        case FunctionCode::ReadFifoQueue:
            if (n != 3) return bad_value(exact_size(n, 3));
            out.address = load_be16(p + 1);
            return {};
        case FunctionCode::EncapsulatedInterface:
            return decode_mei(p, n, out);
    }
    return bad_function(CodecError::UnsupportedFunction);
}

EncodeResult encode_request(const Request& req, MutableBytes out, bool allow_invalid) noexcept {
    // The load engine's hot path: reads need no round trip through the decoder.
    const unsigned read_index = req.function - 1u;
    if (read_index < 4u) {
        if (out.size() < 5) return {0, CodecError::BufferTooSmall};
        const std::uint16_t max =
            read_index < 2u ? limits::kMaxReadBits : limits::kMaxReadRegisters;
        if (!allow_invalid && (static_cast<std::uint16_t>(req.quantity - 1u) >= max ||
                               !range_fits(req.address, req.quantity))) {
            return {0, CodecError::InvalidArgument};
        }
        std::uint8_t* p = out.data();
        p[0] = req.function;
        store_be16(p + 1, req.address);
        store_be16(p + 3, req.quantity);
        return {5, CodecError::Ok};
    }
    if (!allow_invalid && !is_supported_function(req.function)) {
        return {0, CodecError::InvalidArgument};
    }
    const EncodeResult written = encode_raw(req, out);
    if (!written.ok() || allow_invalid) return written;
    // One place per fact: the decoder's checks are the encoder's checks.
    Request check;
    if (!decode_request(Bytes(out.data(), written.size), check).ok()) {
        return {0, CodecError::InvalidArgument};
    }
    return written;
}

EncodeResult encode_read_request(std::uint8_t function, std::uint16_t address,
                                 std::uint16_t quantity, MutableBytes out) noexcept {
    if (out.size() < 5) return {0, CodecError::BufferTooSmall};
    std::uint8_t* p = out.data();
    p[0] = function;
    store_be16(p + 1, address);
    store_be16(p + 3, quantity);
    return {5, CodecError::Ok};
}

std::size_t request_pdu_size(std::uint8_t fc, std::uint16_t quantity,
                             std::uint16_t write_quantity) noexcept {
    const FunctionInfo* f = function_info(fc);
    if (f == nullptr) return limits::kMaxPdu;
    switch (f->request) {
        case RequestShape::FunctionOnly:
            return 1;
        case RequestShape::AddressQuantity:
        case RequestShape::SingleCoil:
        case RequestShape::SingleRegister:
        case RequestShape::SubFunction:
            return 5;
        case RequestShape::MultipleCoils:
            return 6 + detail::packed_coil_bytes(quantity);
        case RequestShape::MultipleRegisters:
            return 6 + 2u * quantity;
        case RequestShape::FileRecords:
            return limits::kMaxPdu;
        case RequestShape::MaskWrite:
            return 7;
        case RequestShape::ReadWriteRegisters:
            return 10 + 2u * write_quantity;
        case RequestShape::FifoPointer:
            return 3;
        case RequestShape::MeiTransport:
            return 4;
    }
    return limits::kMaxPdu;
}

int expected_read_byte_count(const Request& req) noexcept {
    const FunctionInfo* f = function_info(req.function);
    if (f == nullptr) return -1;
    switch (f->response) {
        case ResponseShape::Bits:
            return static_cast<int>(detail::packed_coil_bytes(req.quantity));
        case ResponseShape::Registers:
            return 2 * static_cast<int>(req.quantity);
        case ResponseShape::EchoValue:
        case ResponseShape::EchoQuantity:
        case ResponseShape::EchoMask:
        case ResponseShape::EchoSubFunction:
        case ResponseShape::ExceptionStatus:
        case ResponseShape::EventCounter:
        case ResponseShape::EventLog:
        case ResponseShape::ServerId:
        case ResponseShape::FileRecords:
        case ResponseShape::FifoValues:
        case ResponseShape::MeiObjects:
            return -1;  // no fixed data size
    }
    return -1;
}

}  // namespace mbstorm::codec
