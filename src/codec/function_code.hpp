// Public Modbus function codes and the facts about them that every layer asks for.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

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
