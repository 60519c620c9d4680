#include "cli/frame_describe.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>

#include "codec/exception_code.hpp"
#include "codec/function_code.hpp"
#include "codec/limits.hpp"
#include "codec/pdu.hpp"
#include "codec/rtu.hpp"
#include "codec/values.hpp"

namespace mbstorm::cli {
namespace {

using codec::Bytes;

// Walks the PDU left to right, one row per field, so the hex column always shows the
// exact bytes the meaning was read from.
class RowWriter {
  public:
    RowWriter(Bytes pdu, std::vector<FieldRow>& rows) : pdu_(pdu), rows_(rows) {}

    void field(const std::string& name, std::size_t width, const std::string& meaning) {
        width = std::min(width, pdu_.size() - pos_);
        rows_.push_back({name, codec::format_hex(pdu_.subspan(pos_, width)), meaning});
        pos_ += width;
    }
    void u8(const std::string& name, const std::string& extra = {}) {
        if (pos_ >= pdu_.size()) return;
        std::uint8_t v = pdu_[pos_];
        field(name, 1, extra.empty() ? fmt::format("{}", v) : fmt::format("{} {}", v, extra));
    }
    void u16(const std::string& name, const std::string& extra = {}) {
        if (pos_ + 2 > pdu_.size()) return;
        std::uint16_t v = codec::load_be16(pdu_.data() + pos_);
        field(name, 2,
              extra.empty() ? fmt::format("{} (0x{:04X})", v, v)
                            : fmt::format("{} (0x{:04X}) {}", v, v, extra));
    }
    // Register values, one row each, numbered from the first address.
    void registers(const std::string& name, std::size_t count, int first_address) {
        for (std::size_t i = 0; i < count && pos_ + 2 <= pdu_.size(); ++i) {
            std::string label =
                first_address >= 0
                    ? fmt::format("{} [{}]", name, first_address + static_cast<int>(i))
                    : fmt::format("{} {}", name, i + 1);
            u16(label);
        }
    }
    // Packed bits, one row per byte, showing which bit numbers are on (LSB first).
    void bits(const std::string& name, std::size_t byte_count, int first_address) {
        for (std::size_t i = 0; i < byte_count && pos_ < pdu_.size(); ++i) {
            std::uint8_t b = pdu_[pos_];
            std::string on;
            for (int bit = 0; bit < 8; ++bit) {
                if (b & (1u << bit)) {
                    int n = static_cast<int>(i * 8) + bit + std::max(first_address, 0);
                    on += (on.empty() ? "" : ",") + std::to_string(n);
                }
            }
            field(fmt::format("{} byte {}", name, i + 1), 1,
                  fmt::format("{:08b}{}", b, on.empty() ? "" : " on: " + on));
        }
    }
    void rest(const std::string& name) {
        if (pos_ < pdu_.size()) field(name, pdu_.size() - pos_, byte_count(pdu_.size() - pos_));
    }
    std::size_t pos() const { return pos_; }

  private:
    Bytes pdu_;
    std::vector<FieldRow>& rows_;
    std::size_t pos_ = 0;
};

const char* coil_meaning(std::uint16_t value) {
    if (value == 0xFF00) return "ON";
    if (value == 0x0000) return "OFF";
    return "(neither ON nor OFF)";
}

// FC14 and FC15 requests and the FC15 response: a byte count, then sub-requests.
void describe_file_sub_requests(Bytes payload, bool with_data, RowWriter& w) {
    w.u8("Byte count");
    codec::FileRecordIterator it(payload, with_data);
    codec::FileSubRequest sub;
    for (int n = 1; it.next(sub) == codec::CodecError::Ok; ++n) {
        w.u8(fmt::format("Sub-req {} reference type", n));
        w.u16(fmt::format("Sub-req {} file number", n));
        w.u16(fmt::format("Sub-req {} record number", n));
        w.u16(fmt::format("Sub-req {} record length", n));
        if (with_data) w.registers(fmt::format("Sub-req {} data", n), sub.record_length, -1);
    }
}

void describe_request_fields(const codec::Request& r, RowWriter& w) {
    using FC = codec::FunctionCode;
    switch (static_cast<FC>(r.function)) {
        case FC::ReadCoils:
        case FC::ReadDiscreteInputs:
            w.u16("Starting address");
            w.u16("Quantity of bits");
            break;
        case FC::ReadHoldingRegisters:
        case FC::ReadInputRegisters:
            w.u16("Starting address");
            w.u16("Quantity of registers");
            break;
        case FC::WriteSingleCoil:
            w.u16("Output address");
            w.u16("Output value", coil_meaning(r.value));
            break;
        case FC::WriteSingleRegister:
            w.u16("Register address");
            w.u16("Register value");
            break;
        case FC::Diagnostics:
            w.u16("Sub-function");
            w.rest("Data");
            break;
        case FC::WriteMultipleCoils:
            w.u16("Starting address");
            w.u16("Quantity of outputs");
            w.u8("Byte count");
            w.bits("Outputs", r.payload.size(), r.address);
            break;
        case FC::WriteMultipleRegisters:
            w.u16("Starting address");
            w.u16("Quantity of registers");
            w.u8("Byte count");
            w.registers("Register", r.quantity, r.address);
            break;
        case FC::ReadFileRecord:
        case FC::WriteFileRecord:
            describe_file_sub_requests(r.payload, r.function == codec::to_byte(FC::WriteFileRecord),
                                       w);
            break;
        case FC::MaskWriteRegister:
            w.u16("Reference address");
            w.u16("AND mask");
            w.u16("OR mask");
            break;
        case FC::ReadWriteMultipleRegisters:
            w.u16("Read starting address");
            w.u16("Quantity to read");
            w.u16("Write starting address");
            w.u16("Quantity to write");
            w.u8("Write byte count");
            w.registers("Write register", r.write_quantity, r.write_address);
            break;
        case FC::ReadFifoQueue:
            w.u16("FIFO pointer address");
            break;
        case FC::EncapsulatedInterface:
            w.u8("MEI type",
                 r.mei_type == codec::kMeiReadDeviceId ? "read device identification" : "");
            w.u8("Read device id code");
            w.u8("Object id");
            break;
        default:
            break;
    }
    w.rest("Unparsed bytes");
}

void describe_response_fields(const codec::Response& r, RowWriter& w, Bytes pdu) {
    using FC = codec::FunctionCode;
    switch (static_cast<FC>(r.function)) {
        case FC::ReadCoils:
        case FC::ReadDiscreteInputs:
            w.u8("Byte count");
            w.bits("Status", r.payload.size(), -1);
            break;
        case FC::ReadHoldingRegisters:
        case FC::ReadInputRegisters:
        case FC::ReadWriteMultipleRegisters:
            w.u8("Byte count");
            w.registers("Register value", r.payload.size() / 2, -1);
            break;
        case FC::WriteSingleCoil:
            w.u16("Output address");
            w.u16("Output value", coil_meaning(r.value));
            break;
        case FC::WriteSingleRegister:
            w.u16("Register address");
            w.u16("Register value");
            break;
        case FC::ReadExceptionStatus:
            w.u8("Output data");
            break;
        case FC::Diagnostics:
            w.u16("Sub-function");
            w.rest("Data");
            break;
        case FC::GetCommEventCounter:
            w.u16("Status");
            w.u16("Event count");
            break;
        case FC::GetCommEventLog:
            w.u8("Byte count");
            w.u16("Status");
            w.u16("Event count");
            w.u16("Message count");
            w.rest("Events");
            break;
        case FC::WriteMultipleCoils:
        case FC::WriteMultipleRegisters:
            w.u16("Starting address");
            w.u16("Quantity");
            break;
        case FC::ReportServerId:
            w.u8("Byte count");
            w.rest("Server id and run indicator");
            break;
        case FC::ReadFileRecord: {
            w.u8("Response data length");
            codec::FileResponseIterator it(r.payload);
            codec::FileSubResponse sub;
            for (int n = 1; it.next(sub) == codec::CodecError::Ok; ++n) {
                w.u8(fmt::format("Sub-rsp {} length", n));
                w.u8(fmt::format("Sub-rsp {} reference type", n));
                w.registers(fmt::format("Sub-rsp {} data", n), sub.record_data.size() / 2, -1);
            }
            break;
        }
        case FC::WriteFileRecord:  // the response echoes the request
            describe_file_sub_requests(r.payload, true, w);
            break;
        case FC::MaskWriteRegister:
            w.u16("Reference address");
            w.u16("AND mask");
            w.u16("OR mask");
            break;
        case FC::ReadFifoQueue:
            w.u16("Byte count");
            w.u16("FIFO count");
            w.registers("FIFO value", r.fifo_count, -1);
            break;
        case FC::EncapsulatedInterface: {
            w.u8("MEI type");
            w.u8("Read device id code");
            w.u8("Conformity level");
            w.u8("More follows", r.more_follows ? "(more)" : "(last)");
            w.u8("Next object id");
            w.u8("Number of objects");
            codec::DeviceIdObjectIterator it(r.payload);
            codec::DeviceIdObject obj;
            while (it.next(obj) == codec::CodecError::Ok) {
                w.u8("Object id");
                w.u8("Object length");
                std::string text(obj.value.begin(), obj.value.end());
                w.field("Object value", obj.value.size(), fmt::format("\"{}\"", text));
            }
            break;
        }
        default:
            break;
    }
    (void)pdu;
    w.rest("Unparsed bytes");
}

std::uint16_t be16_at(Bytes pdu, std::size_t at) {
    return at + 2 <= pdu.size() ? codec::load_be16(pdu.data() + at) : 0;
}
Bytes bytes_from(Bytes pdu, std::size_t at) {
    return at < pdu.size() ? pdu.subspan(at) : Bytes{};
}

// The fields of a request read straight from the bytes, without any validation, so a PDU the
// decoder refuses can still be shown field by field.
codec::Request raw_request(Bytes pdu) {
    codec::Request r;
    r.function = pdu[0];
    r.address = be16_at(pdu, 1);
    r.quantity = be16_at(pdu, 3);
    r.value = be16_at(pdu, 3);
    r.write_address = be16_at(pdu, 5);
    r.write_quantity = be16_at(pdu, 7);
    r.mei_type = pdu.size() > 1 ? pdu[1] : 0;
    using FC = codec::FunctionCode;
    switch (static_cast<FC>(r.function)) {
        case FC::WriteMultipleCoils:
            r.payload = bytes_from(pdu, 6);
            break;
        case FC::ReadFileRecord:
        case FC::WriteFileRecord:
            r.payload = bytes_from(pdu, 2);
            break;
        default:
            break;
    }
    return r;
}

codec::Response raw_response(Bytes pdu) {
    codec::Response r;
    r.function = pdu[0] & ~codec::kExceptionBit;
    if (pdu[0] & codec::kExceptionBit) r.exception = codec::ExceptionCode::IllegalFunction;
    r.value = be16_at(pdu, 3);
    r.fifo_count = be16_at(pdu, 3);
    using FC = codec::FunctionCode;
    switch (static_cast<FC>(r.function)) {
        case FC::ReadCoils:
        case FC::ReadDiscreteInputs:
        case FC::ReadHoldingRegisters:
        case FC::ReadInputRegisters:
        case FC::ReadWriteMultipleRegisters:
        case FC::ReadFileRecord:
        case FC::WriteFileRecord:
            r.payload = bytes_from(pdu, 2);
            break;
        default:
            break;
    }
    return r;
}

// How many bytes a PDU of this function needs, from its fixed layout or its own byte count;
// 0 when that cannot be told. The codec's RTU length rule knows each function's layout: it is
// asked about the PDU behind a placeholder address (the CRC it counts is taken off again).
std::size_t needed_size(Bytes pdu, Direction dir) {
    std::array<std::uint8_t, codec::limits::kMaxRtuAdu> head{};
    const std::size_t copied = std::min(pdu.size(), head.size() - 1);
    std::copy_n(pdu.begin(), copied, head.begin() + 1);
    const Bytes frame(head.data(), copied + 1);
    const codec::RtuLength length = dir == Direction::Response ? codec::rtu_response_length(frame)
                                                               : codec::rtu_request_length(frame);
    constexpr std::size_t kAddressAndCrc = 3;
    if (length.status != codec::RtuLength::Status::Known || length.size < kAddressAndCrc) return 0;
    return length.size - kAddressAndCrc;
}

// A quantity field of a request and the range the specification allows it.
struct QuantityField {
    const char* row;
    std::size_t offset;
    codec::limits::QuantityRange range;
};
std::vector<QuantityField> quantity_fields(std::uint8_t fc) {
    using codec::RequestShape;
    const codec::FunctionInfo* f = codec::function_info(fc);
    if (f == nullptr) return {};
    switch (f->request) {
        case RequestShape::AddressQuantity:
            return {{f->table && codec::is_bit_table(*f->table) ? "Quantity of bits"
                                                                : "Quantity of registers",
                     3, f->quantity}};
        case RequestShape::MultipleRegisters:
            return {{"Quantity of registers", 3, f->quantity}};
        case RequestShape::MultipleCoils:
            return {{"Quantity of outputs", 3, f->quantity}};
        case RequestShape::ReadWriteRegisters:
            return {{"Quantity to read", 3, f->quantity},
                    {"Quantity to write", 7, {1, codec::limits::kMaxRwWriteRegisters}}};
        default:
            return {};
    }
}

// Appends the marker to the first row (from `first` on) whose name starts with `prefix` or
// contains it; false when no row matches.
bool mark_row(std::vector<FieldRow>& rows, std::size_t first, std::string_view name,
              const std::string& why) {
    for (std::size_t i = first; i < rows.size(); ++i) {
        if (rows[i].field.find(name) == std::string::npos) continue;
        rows[i].meaning += "  <-- BAD: " + why;
        return true;
    }
    return false;
}

// Names what is wrong with a PDU the decoder refused, and marks the field that holds it (or
// adds a row saying where the bytes run out). Returns the fault as one phrase.
std::string pdu_fault(Bytes pdu, Direction dir, codec::CodecError error,
                      std::vector<FieldRow>& rows, std::size_t first) {
    using codec::CodecError;
    const std::uint8_t fc = pdu[0] & ~codec::kExceptionBit;
    const std::string fc_text = codec::function_label(fc);
    std::string why;
    std::string_view row;
    switch (error) {
        case CodecError::UnsupportedFunction:
            row = "Function code";
            why = fmt::format("function code 0x{:02X} is not one this tool knows", pdu[0]);
            break;
        case CodecError::Truncated: {
            std::size_t need = needed_size(pdu, dir);
            why = need ? fmt::format("{}: {} needs {}", byte_count(pdu.size()), fc_text, need)
                       : fmt::format("{}: fewer than {} needs", byte_count(pdu.size()), fc_text);
            rows.push_back({"(end of bytes)", "", "<-- BAD: " + why});
            return "truncated: " + why;
        }
        case CodecError::TrailingBytes: {
            row = "Unparsed bytes";
            std::size_t need = needed_size(pdu, dir);
            why = need ? fmt::format("{} bytes: {} needs {}", pdu.size(), fc_text, need)
                       : fmt::format("{} bytes: more than {} needs", pdu.size(), fc_text);
            break;
        }
        case CodecError::QuantityOutOfRange:
            for (const auto& q : quantity_fields(fc)) {
                std::uint16_t v = be16_at(pdu, q.offset);
                if (dir == Direction::Request && (v < q.range.min || v > q.range.max)) {
                    row = q.row;
                    why = fmt::format("quantity {}: valid {}..{} for {}", v, q.range.min,
                                      q.range.max, fc_text);
                    break;
                }
            }
            if (row.empty()) {
                row = codec::request_is(fc, codec::RequestShape::FifoPointer) ? "FIFO count"
                                                                              : "Quantity";
                why = fmt::format("{} for {}", codec::error_description(error), fc_text);
            }
            break;
        case CodecError::ByteCountMismatch:
            row = "yte count";
            why = fmt::format("{} (PDU is {} bytes)", codec::error_description(error), pdu.size());
            break;
        case CodecError::AddressOverflow:
            row = "Quantity";
            why = fmt::format("address {} + quantity {} runs past 65535", be16_at(pdu, 1),
                              be16_at(pdu, 3));
            break;
        case CodecError::InvalidCoilValue:
            row = "Output value";
            why = fmt::format("0x{:04X}: valid 0xFF00 (ON) or 0x0000 (OFF)", be16_at(pdu, 3));
            break;
        case CodecError::UnsupportedSubFunction:
            if (codec::request_is(fc, codec::RequestShape::MeiTransport)) {
                row = "MEI type";
                why = fmt::format("MEI type 0x{:02X}: valid 0x0E (read device identification)",
                                  pdu.size() > 1 ? pdu[1] : 0);
            } else {
                row = "Sub-function";
                why = fmt::format(
                    "sub-function 0x{:04X}: valid 0x0000..0x0004, 0x000A..0x0012, 0x0014",
                    be16_at(pdu, 1));
            }
            break;
        case CodecError::InvalidReferenceType:
            row = "reference type";
            why = "file reference type must be 6";
            break;
        case CodecError::InvalidDeviceIdCode:
            row = "Read device id code";
            why = "read device id code: valid 1..4";
            break;
        case CodecError::InvalidExceptionCode:
            row = "Exception code";
            why = "exception code 0 does not exist";
            break;
        default:
            why = std::string(codec::error_description(error));
            break;
    }
    if (row.empty() || !mark_row(rows, first, row, why))
        rows.push_back({"(fault)", "", "<-- BAD: " + why});
    return why;
}

}  // namespace

bool describe_pdu(Bytes pdu, Direction dir, std::vector<FieldRow>& rows, std::string& error) {
    if (pdu.empty()) {
        error = "empty PDU: no function code";
        return false;
    }
    const std::size_t first = rows.size();
    RowWriter w(pdu, rows);
    if (dir == Direction::Request) {
        codec::Request req;
        auto status = codec::decode_request(pdu, req);
        if (!status.ok()) {
            // Still shown field by field, read straight from the bytes, with the bad field marked.
            codec::Request raw = raw_request(pdu);
            w.field("Function code", 1, codec::function_label(raw.function));
            describe_request_fields(raw, w);
            std::string fault = pdu_fault(pdu, Direction::Request, status.error, rows, first);
            error = fmt::format("not a valid request: {} (a server answers exception {:02X} {})",
                                fault, static_cast<int>(status.exception),
                                codec::exception_name(status.exception));
            return false;
        }
        w.field("Function code", 1, codec::function_label(req.function));
        describe_request_fields(req, w);
        return true;
    }
    codec::Response rsp;
    auto err = codec::decode_response(pdu, rsp);
    if (err != codec::CodecError::Ok) {
        codec::Response raw = raw_response(pdu);
        if (raw.exception != codec::ExceptionCode::None) {
            w.field(
                "Function code", 1,
                fmt::format("0x{:02X} = 0x80 | {}: exception", raw.function | codec::kExceptionBit,
                            codec::function_label(raw.function)));
            w.u8("Exception code");
            w.rest("Unparsed bytes");
        } else {
            w.field("Function code", 1, codec::function_label(raw.function));
            describe_response_fields(raw, w, pdu);
        }
        error = fmt::format("not a valid response: {}",
                            pdu_fault(pdu, Direction::Response, err, rows, first));
        return false;
    }
    if (rsp.exception != codec::ExceptionCode::None) {
        w.field("Function code", 1,
                fmt::format("0x{:02X} = 0x80 | {}: exception", rsp.function | codec::kExceptionBit,
                            codec::function_label(rsp.function)));
        w.u8("Exception code", std::string(codec::exception_name(rsp.exception)));
        w.rest("Unparsed bytes");
        return true;
    }
    w.field("Function code", 1, codec::function_label(rsp.function));
    describe_response_fields(rsp, w, pdu);
    return true;
}

std::string request_fault(Bytes pdu) {
    std::vector<FieldRow> rows;
    if (pdu.empty()) return "empty PDU: no function code";
    codec::Request req;
    auto status = codec::decode_request(pdu, req);
    if (status.ok()) return {};
    RowWriter w(pdu, rows);
    codec::Request raw = raw_request(pdu);
    w.field("Function code", 1, codec::function_label(raw.function));
    describe_request_fields(raw, w);
    return pdu_fault(pdu, Direction::Request, status.error, rows, 0);
}

std::string byte_count(std::size_t n) {
    return fmt::format("{} byte{}", n, n == 1 ? "" : "s");
}

std::string render_rows(const std::vector<FieldRow>& rows) {
    std::size_t field_w = 5, hex_w = 5;
    for (const auto& r : rows) {
        field_w = std::max(field_w, r.field.size());
        hex_w = std::max(hex_w, std::min<std::size_t>(r.hex.size(), 24));
    }
    std::string out =
        fmt::format("  {:<{}}  {:<{}}  {}\n", "Field", field_w, "Bytes", hex_w, "Meaning");
    for (const auto& r : rows) {
        out += fmt::format("  {:<{}}  {:<{}}  {}\n", r.field, field_w, r.hex, hex_w, r.meaning);
    }
    return out;
}

}  // namespace mbstorm::cli
