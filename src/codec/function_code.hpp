// Public Modbus function codes and the facts about them that every layer asks for: one
// descriptor table (public_functions()) that other layers iterate or query instead of naming
// codes. Adding a public function code means a row here, its encode/decode in pdu_*.cpp (the
// switches there are over FunctionCode, so -Wswitch lists what is missing) and a slave handler.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "codec/limits.hpp"
#include "codec/table.hpp"

namespace mbstorm::codec {

enum class FunctionCode : std::uint8_t {
    ReadCoils = 0x01,
    ReadDiscreteInputs = 0x02,
    ReadHoldingRegisters = 0x03,
    ReadInputRegisters = 0x04,
    WriteSingleCoil = 0x05,
    WriteSingleRegister = 0x06,
    ReadExceptionStatus = 0x07,
    Diagnostics = 0x08,
    GetCommEventCounter = 0x0B,
    GetCommEventLog = 0x0C,
    WriteMultipleCoils = 0x0F,
    WriteMultipleRegisters = 0x10,
    ReportServerId = 0x11,
    ReadFileRecord = 0x14,
    WriteFileRecord = 0x15,
    MaskWriteRegister = 0x16,
    ReadWriteMultipleRegisters = 0x17,
    ReadFifoQueue = 0x18,
    EncapsulatedInterface = 0x2B,
};

constexpr std::uint8_t to_byte(FunctionCode fc) noexcept {
    return static_cast<std::uint8_t>(fc);
}

// Set on the function code of an exception response.
inline constexpr std::uint8_t kExceptionBit = 0x80;

// What a request carries after the function code. Generators and checkers switch over shapes,
// not codes, so a new function of a known shape needs no change outside codec/.
enum class RequestShape : std::uint8_t {
    FunctionOnly,        // 07, 0B, 0C, 11
    AddressQuantity,     // 01-04: start, count
    SingleCoil,          // 05: address, 0xFF00 or 0x0000
    SingleRegister,      // 06: address, value
    SubFunction,         // 08: sub-function, data
    MultipleCoils,       // 0F: start, count, byte count, packed bits
    MultipleRegisters,   // 10: start, count, byte count, registers
    FileRecords,         // 14, 15: byte count, sub-requests
    MaskWrite,           // 16: address, AND mask, OR mask
    ReadWriteRegisters,  // 17: read start/count, write start/count, byte count, registers
    FifoPointer,         // 18: FIFO pointer address
    MeiTransport,        // 2B: MEI type and its data
};

// What a normal response carries.
enum class ResponseShape : std::uint8_t {
    Bits,             // 01, 02: byte count, packed bits
    Registers,        // 03, 04, 17: byte count, registers
    EchoValue,        // 05, 06: address and value echoed
    EchoQuantity,     // 0F, 10: address and quantity echoed
    EchoMask,         // 16: address and both masks echoed
    EchoSubFunction,  // 08: sub-function and data echoed
    ExceptionStatus,  // 07: one status byte
    EventCounter,     // 0B: status, event count
    EventLog,         // 0C: byte count, status, counters, events
    ServerId,         // 11: byte count, server id bytes
    FileRecords,      // 14: sub-responses; 15: the request echoed
    FifoValues,       // 18: byte count, FIFO count, values
    MeiObjects,       // 2B: MEI type and its objects
};

// The specification's grouping: data access reads and writes, and diagnostics.
enum class FunctionKind : std::uint8_t { Read, Write, Diagnostic };

struct FunctionInfo {
    FunctionCode code;
    std::string_view name;  // snake_case, e.g. "read_holding_registers"
    FunctionKind kind;
    bool writes;                     // changes the device's state (08 restarts and clears counters)
    std::optional<Table> table;      // the table its address points into; nullopt: no address
    limits::QuantityRange quantity;  // max 0: no quantity; FC17: the read part
    RequestShape request;
    ResponseShape response;
};

// Every public function code this codec encodes and decodes, in code order.
std::span<const FunctionInfo> public_functions() noexcept;
// The same codes as bytes, in code order (what a fuzzer walks).
std::span<const std::uint8_t> public_function_codes() noexcept;
// The descriptor of `fc`; nullptr for codes this codec does not know.
const FunctionInfo* function_info(std::uint8_t fc) noexcept;

// The quantity a request of function `fc` may ask for (FC17: the read part); {0, 0} when the
// function takes no quantity or is unknown. Load plans and scenarios validate against this.
limits::QuantityRange quantity_range(std::uint8_t fc) noexcept;

// The table a function code addresses; nullopt for functions without an address.
std::optional<Table> function_table(std::uint8_t fc) noexcept;

// The function whose request has `shape` and addresses `table`: the read of holding registers
// (AddressQuantity) is 03, the single write of coils (SingleCoil) 05; 0 when there is none.
std::uint8_t function_for(Table table, RequestShape shape) noexcept;

// Where a request of `shape` carries its addresses: PDU offsets of the big-endian start
// address fields (FC 17: the read range's, then the write range's), 0 for none.
struct AddressFields {
    std::size_t first = 0, second = 0;
    bool any() const noexcept { return first != 0; }
};
AddressFields address_fields(RequestShape shape) noexcept;

// Where a request of function `fc` carries the fields a server checks besides its addresses:
// PDU offsets of the quantity (FC 17: the read count), of the count its byte count follows
// (FC 0F, 10: the quantity itself; FC 17: the write count), of the byte count, of the first
// data byte and of FC 05's value (0000 or FF00 only); 0 for none. With the range each count
// must lie in, and how many data bytes `n` items take.
struct RequestFields {
    std::size_t quantity = 0, written = 0, byte_count = 0, data = 0, coil_value = 0;
    limits::QuantityRange quantity_range, written_range;
    bool packed_bits = false;  // data is packed coils, else 2 bytes per register
    std::size_t data_bytes(std::uint16_t n) const noexcept {
        return packed_bits ? (std::size_t{n} + 7u) / 8u : 2u * std::size_t{n};
    }
};
RequestFields request_fields(std::uint8_t fc) noexcept;

// True when `fc` is public and its request (response) has `shape`.
bool request_is(std::uint8_t fc, RequestShape shape) noexcept;
bool response_is(std::uint8_t fc, ResponseShape shape) noexcept;

// True for the function codes this codec encodes and decodes.
bool is_supported_function(std::uint8_t fc) noexcept;
// True for function codes that change a device's state (05, 06, 08, 0F, 10, 15, 16, 17).
bool is_write_function(std::uint8_t fc) noexcept;
// snake_case name, e.g. "read_holding_registers"; "" for unsupported codes.
std::string_view function_name(std::uint8_t fc) noexcept;
// Inverse of function_name; returns false when the name is unknown.
bool function_from_name(std::string_view name, std::uint8_t& fc) noexcept;

// How every output names a function code: "0x10 write_multiple_registers"; "0x41" for codes
// without a name. Hex with a prefix, so 0x16 never reads as sixteen.
std::string function_label(std::uint8_t fc);

// The forms a user may write a function code in, for --help texts and documentation.
inline constexpr std::string_view kFunctionCodeForms =
    "a name (write_multiple_registers), hex with 0x (0x10) or decimal (16)";

// Reads a function code the way a user writes it (see kFunctionCodeForms), 1..127. Returns ""
// on success, else one line naming the value and the forms accepted. Does not check that the
// code is supported: callers that need that say so themselves.
std::string parse_function_code(std::string_view text, std::uint8_t& fc);

// Diagnostics (FC 08) sub-functions the codec knows.
enum class DiagnosticSubFunction : std::uint16_t {
    ReturnQueryData = 0x0000,
    RestartCommunications = 0x0001,
    ReturnDiagnosticRegister = 0x0002,
    ChangeAsciiDelimiter = 0x0003,
    ForceListenOnlyMode = 0x0004,
    ClearCounters = 0x000A,
    ReturnBusMessageCount = 0x000B,
    ReturnBusCommunicationErrorCount = 0x000C,
    ReturnBusExceptionErrorCount = 0x000D,
    ReturnServerMessageCount = 0x000E,
    ReturnServerNoResponseCount = 0x000F,
    ReturnServerNakCount = 0x0010,
    ReturnServerBusyCount = 0x0011,
    ReturnBusCharacterOverrunCount = 0x0012,
    ClearOverrunCounterAndFlag = 0x0014,
};

// MEI types carried by FC 0x2B.
inline constexpr std::uint8_t kMeiCanOpen = 0x0D;
inline constexpr std::uint8_t kMeiReadDeviceId = 0x0E;

}  // namespace mbstorm::codec
