#include "cli/frame_describe.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>

#include "codec/exception_code.hpp"
#include "codec/function_code.hpp"
#include "codec/limits.hpp"
#include "codec/pdu.hpp"
#include "codec/pdu_layout.hpp"
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
    // The next byte or big-endian word, without taking it; 0 past the end.
    std::uint8_t next_byte() const { return pos_ < pdu_.size() ? pdu_[pos_] : 0; }
    std::uint16_t next_word() const {
        return pos_ + 2 <= pdu_.size() ? codec::load_be16(pdu_.data() + pos_) : 0;
    }

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

// The counts and first addresses a layout's fields refer to, from a request or a response.
struct LayoutValues {
    Bytes payload;
    std::size_t quantity = 0, write_quantity = 0, fifo_count = 0;
    int address = -1, write_address = -1;
    bool more_follows = false;
};

LayoutValues values_of(const codec::Request& r) {
    return {r.payload, r.quantity, r.write_quantity, 0, r.address, r.write_address, false};
}
LayoutValues values_of(const codec::Response& r) {
    return {r.payload, 0, 0, r.fifo_count, -1, -1, r.more_follows != 0};
}

std::size_t item_count(const codec::PduField& f, const LayoutValues& v) {
    using codec::FieldCount;
    switch (f.count) {
        case FieldCount::One:
            return 1;
        case FieldCount::PayloadBytes:
            return v.payload.size();
        case FieldCount::PayloadWords:
            return v.payload.size() / 2;
        case FieldCount::Quantity:
            return v.quantity;
        case FieldCount::WriteQuantity:
            return v.write_quantity;
        case FieldCount::FifoCount:
            return v.fifo_count;
    }
    return 1;
}

// The address of a field's first item, or -1 when its items are numbered 1, 2, ...
int first_address(const codec::PduField& f, const LayoutValues& v) {
    using codec::FieldNumbering;
    switch (f.numbering) {
        case FieldNumbering::Ordinal:
            return -1;
        case FieldNumbering::FromAddress:
            return v.address;
        case FieldNumbering::FromWriteAddress:
            return v.write_address;
    }
    return -1;
}

// FC14 and FC15 sub-requests (FC15's answer echoes them), after the byte count.
void describe_file_sub_requests(Bytes payload, bool with_data, RowWriter& w) {
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

void describe_file_sub_responses(Bytes payload, RowWriter& w) {
    codec::FileResponseIterator it(payload);
    codec::FileSubResponse sub;
    for (int n = 1; it.next(sub) == codec::CodecError::Ok; ++n) {
        w.u8(fmt::format("Sub-rsp {} length", n));
        w.u8(fmt::format("Sub-rsp {} reference type", n));
        w.registers(fmt::format("Sub-rsp {} data", n), sub.record_data.size() / 2, -1);
    }
}

void describe_device_id_objects(Bytes payload, RowWriter& w) {
    codec::DeviceIdObjectIterator it(payload);
    codec::DeviceIdObject obj;
    while (it.next(obj) == codec::CodecError::Ok) {
        w.u8("Object id");
        w.u8("Object length");
        std::string text(obj.value.begin(), obj.value.end());
        w.field("Object value", obj.value.size(), fmt::format("\"{}\"", text));
    }
}

void describe_field(const codec::PduField& f, const LayoutValues& v, RowWriter& w) {
    using codec::FieldKind;
    const std::string name(f.name);
    switch (f.kind) {
        case FieldKind::Byte:
            w.u8(name);
            break;
        case FieldKind::Word:
            w.u16(name);
            break;
        case FieldKind::CoilValue:
            w.u16(name, coil_meaning(w.next_word()));
            break;
        case FieldKind::MeiType:
            w.u8(name,
                 w.next_byte() == codec::kMeiReadDeviceId ? "read device identification" : "");
            break;
        case FieldKind::MoreFollows:
            w.u8(name, v.more_follows ? "(more)" : "(last)");
            break;
        case FieldKind::Registers:
            w.registers(name, item_count(f, v), first_address(f, v));
            break;
        case FieldKind::PackedBits:
            w.bits(name, item_count(f, v), first_address(f, v));
            break;
        case FieldKind::Rest:
            w.rest(name);
            break;
        case FieldKind::FileSubRequests:
        case FieldKind::FileSubRequestsWithData:
            describe_file_sub_requests(v.payload, f.kind == FieldKind::FileSubRequestsWithData, w);
            break;
        case FieldKind::FileSubResponses:
            describe_file_sub_responses(v.payload, w);
            break;
        case FieldKind::DeviceIdObjects:
            describe_device_id_objects(v.payload, w);
            break;
    }
}

// The fields after the function code, as the codec lays them out for this function, then
// whatever the layout does not account for.
void describe_layout(const codec::PduLayout& layout, const LayoutValues& v, RowWriter& w) {
    for (const codec::PduField& f : layout.fields) describe_field(f, v, w);
    w.rest("Unparsed bytes");
}

void describe_request_fields(const codec::Request& r, RowWriter& w) {
    const codec::FunctionInfo* f = codec::function_info(r.function);
    describe_layout(f != nullptr ? codec::request_layout(*f) : codec::PduLayout{}, values_of(r), w);
}

void describe_response_fields(const codec::Response& r, RowWriter& w) {
    const codec::FunctionInfo* f = codec::function_info(r.function);
    describe_layout(f != nullptr ? codec::response_layout(*f) : codec::PduLayout{}, values_of(r),
                    w);
}

std::uint16_t be16_at(Bytes pdu, std::size_t at) {
    return at + 2 <= pdu.size() ? codec::load_be16(pdu.data() + at) : 0;
}
Bytes bytes_from(Bytes pdu, std::size_t at) {
    return at < pdu.size() ? pdu.subspan(at) : Bytes{};
}

// Where the variable part of a PDU the decoder refused begins, by the codec's layout.
Bytes raw_payload(Bytes pdu, std::uint8_t fc, Direction dir) {
    const codec::FunctionInfo* f = codec::function_info(fc);
    if (f == nullptr) return {};
    const codec::PduLayout layout =
        dir == Direction::Request ? codec::request_layout(*f) : codec::response_layout(*f);
    return layout.payload_at != 0 ? bytes_from(pdu, layout.payload_at) : Bytes{};
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
    r.payload = raw_payload(pdu, r.function, Direction::Request);
    return r;
}

codec::Response raw_response(Bytes pdu) {
    codec::Response r;
    r.function = pdu[0] & ~codec::kExceptionBit;
    if (pdu[0] & codec::kExceptionBit) r.exception = codec::ExceptionCode::IllegalFunction;
    r.value = be16_at(pdu, 3);
    r.fifo_count = be16_at(pdu, 3);
    r.payload = raw_payload(pdu, r.function, Direction::Response);
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
    std::string_view row;
    std::size_t offset;
    codec::limits::QuantityRange range;
};
// The name the layout gives the request field at PDU offset `at`; "" when none starts there.
std::string_view request_field_at(const codec::FunctionInfo& f, std::size_t at) {
    std::size_t offset = 1;  // after the function code
    for (const codec::PduField& field : codec::request_layout(f).fields) {
        if (offset == at) return field.name;
        const std::size_t width = codec::fixed_width(field.kind);
        if (width == 0) break;
        offset += width;
    }
    return {};
}

// The request's count fields (the codec's request_fields) and their ranges.
std::vector<QuantityField> quantity_fields(std::uint8_t fc) {
    const codec::FunctionInfo* f = codec::function_info(fc);
    if (f == nullptr) return {};
    const codec::RequestFields at = codec::request_fields(fc);
    std::vector<QuantityField> fields;
    if (at.quantity != 0)
        fields.push_back({request_field_at(*f, at.quantity), at.quantity, at.quantity_range});
    if (at.written != 0 && at.written != at.quantity)
        fields.push_back({request_field_at(*f, at.written), at.written, at.written_range});
    return fields;
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

Error describe_pdu(Bytes pdu, Direction dir, std::vector<FieldRow>& rows) {
    if (pdu.empty()) return Error(ErrorCode::InvalidInput, "empty PDU: no function code");
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
            return Error(ErrorCode::InvalidInput,
                         fmt::format("not a valid request: {} (a server answers exception {:02X} "
                                     "{})",
                                     fault, static_cast<int>(status.exception),
                                     codec::exception_name(status.exception)));
        }
        w.field("Function code", 1, codec::function_label(req.function));
        describe_request_fields(req, w);
        return Error::none();
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
            describe_response_fields(raw, w);
        }
        return Error(ErrorCode::InvalidInput,
                     fmt::format("not a valid response: {}",
                                 pdu_fault(pdu, Direction::Response, err, rows, first)));
    }
    if (rsp.exception != codec::ExceptionCode::None) {
        w.field("Function code", 1,
                fmt::format("0x{:02X} = 0x80 | {}: exception", rsp.function | codec::kExceptionBit,
                            codec::function_label(rsp.function)));
        w.u8("Exception code", std::string(codec::exception_name(rsp.exception)));
        w.rest("Unparsed bytes");
        return Error::none();
    }
    w.field("Function code", 1, codec::function_label(rsp.function));
    describe_response_fields(rsp, w);
    return Error::none();
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
