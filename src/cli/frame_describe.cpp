#include "cli/frame_describe.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "codec/exception_code.hpp"
#include "codec/function_code.hpp"
#include "codec/pdu.hpp"
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
        if (pos_ < pdu_.size())
            field(name, pdu_.size() - pos_, fmt::format("{} bytes", pdu_.size() - pos_));
    }
    std::size_t pos() const { return pos_; }

  private:
    Bytes pdu_;
    std::vector<FieldRow>& rows_;
    std::size_t pos_ = 0;
};

std::string function_label(std::uint8_t fc) {
    auto name = codec::function_name(fc);
    return name.empty() ? std::string("(unsupported)") : std::string(name);
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
            w.u16("Output value", r.value == 0xFF00 ? "ON" : "OFF");
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
            w.u16("Output value", r.value == 0xFF00 ? "ON" : "OFF");
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

}  // namespace

bool describe_pdu(Bytes pdu, Direction dir, std::vector<FieldRow>& rows, std::string& error) {
    if (pdu.empty()) {
        error = "empty PDU: no function code";
        return false;
    }
    RowWriter w(pdu, rows);
    if (dir == Direction::Request) {
        codec::Request req;
        auto status = codec::decode_request(pdu, req);
        if (!status.ok()) {
            error = fmt::format("not a valid request: {} (a server answers exception {:02X} {})",
                                codec::error_description(status.error),
                                static_cast<int>(status.exception),
                                codec::exception_name(status.exception));
            return false;
        }
        w.u8("Function code", function_label(req.function));
        describe_request_fields(req, w);
        return true;
    }
    codec::Response rsp;
    auto err = codec::decode_response(pdu, rsp);
    if (err != codec::CodecError::Ok) {
        error = fmt::format("not a valid response: {}", codec::error_description(err));
        return false;
    }
    if (rsp.exception != codec::ExceptionCode::None) {
        w.u8("Function code", fmt::format("= 0x{:02X} | 0x80: exception to {}", rsp.function,
                                          function_label(rsp.function)));
        w.u8("Exception code", std::string(codec::exception_name(rsp.exception)));
        w.rest("Unparsed bytes");
        return true;
    }
    w.u8("Function code", function_label(rsp.function));
    describe_response_fields(rsp, w, pdu);
    return true;
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
