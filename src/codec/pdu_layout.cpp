// The field layouts of the request and response shapes (see pdu_layout.hpp). The switches are
// over the shapes without a default, so a new shape does not compile until it is described.
#include "codec/pdu_layout.hpp"

#include <array>

#include "codec/values.hpp"

namespace mbstorm::codec {
namespace {

using enum FieldKind;
using FieldCount::FifoCount;
using FieldCount::PayloadBytes;
using FieldCount::PayloadWords;
using FieldCount::Quantity;
using FieldCount::WriteQuantity;
using FieldNumbering::FromAddress;
using FieldNumbering::FromWriteAddress;
using FieldNumbering::Ordinal;

// The first bytes of the variable part, after the fixed fields before it.
constexpr std::size_t kAfterByteCount = 2;        // function code, byte count
constexpr std::size_t kAfterCoilWriteHeader = 6;  // code, start, quantity, byte count

constexpr std::array<PduField, 2> kReadBits{
    {{"Starting address", Word}, {"Quantity of bits", Word}}};
constexpr std::array<PduField, 2> kReadRegisters{
    {{"Starting address", Word}, {"Quantity of registers", Word}}};
constexpr std::array<PduField, 2> kSingleCoil{
    {{"Output address", Word}, {"Output value", CoilValue}}};
constexpr std::array<PduField, 2> kSingleRegister{
    {{"Register address", Word}, {"Register value", Word}}};
constexpr std::array<PduField, 2> kSubFunction{{{"Sub-function", Word}, {"Data", Rest}}};
constexpr std::array<PduField, 4> kWriteCoils{{{"Starting address", Word},
                                               {"Quantity of outputs", Word},
                                               {"Byte count", Byte},
                                               {"Outputs", PackedBits, PayloadBytes, FromAddress}}};
constexpr std::array<PduField, 4> kWriteRegisters{{{"Starting address", Word},
                                                   {"Quantity of registers", Word},
                                                   {"Byte count", Byte},
                                                   {"Register", Registers, Quantity, FromAddress}}};
constexpr std::array<PduField, 2> kFileRead{
    {{"Byte count", Byte}, {"Sub-requests", FileSubRequests}}};
constexpr std::array<PduField, 2> kFileWrite{
    {{"Byte count", Byte}, {"Sub-requests", FileSubRequestsWithData}}};
constexpr std::array<PduField, 3> kMaskWrite{
    {{"Reference address", Word}, {"AND mask", Word}, {"OR mask", Word}}};
constexpr std::array<PduField, 6> kReadWrite{
    {{"Read starting address", Word},
     {"Quantity to read", Word},
     {"Write starting address", Word},
     {"Quantity to write", Word},
     {"Write byte count", Byte},
     {"Write register", Registers, WriteQuantity, FromWriteAddress}}};
constexpr std::array<PduField, 1> kFifoPointer{{{"FIFO pointer address", Word}}};
constexpr std::array<PduField, 3> kMeiRequest{
    {{"MEI type", MeiType}, {"Read device id code", Byte}, {"Object id", Byte}}};

constexpr std::array<PduField, 2> kBitsAnswer{
    {{"Byte count", Byte}, {"Status", PackedBits, PayloadBytes, Ordinal}}};
constexpr std::array<PduField, 2> kRegistersAnswer{
    {{"Byte count", Byte}, {"Register value", Registers, PayloadWords, Ordinal}}};
constexpr std::array<PduField, 2> kEchoQuantity{{{"Starting address", Word}, {"Quantity", Word}}};
constexpr std::array<PduField, 1> kExceptionStatus{{{"Output data", Byte}}};
constexpr std::array<PduField, 2> kEventCounter{{{"Status", Word}, {"Event count", Word}}};
constexpr std::array<PduField, 5> kEventLog{{{"Byte count", Byte},
                                             {"Status", Word},
                                             {"Event count", Word},
                                             {"Message count", Word},
                                             {"Events", Rest}}};
constexpr std::array<PduField, 2> kServerId{
    {{"Byte count", Byte}, {"Server id and run indicator", Rest}}};
constexpr std::array<PduField, 2> kFileReadAnswer{
    {{"Response data length", Byte}, {"Sub-responses", FileSubResponses}}};
constexpr std::array<PduField, 3> kFifoAnswer{
    {{"Byte count", Word}, {"FIFO count", Word}, {"FIFO value", Registers, FifoCount, Ordinal}}};
constexpr std::array<PduField, 7> kMeiAnswer{{{"MEI type", Byte},
                                              {"Read device id code", Byte},
                                              {"Conformity level", Byte},
                                              {"More follows", MoreFollows},
                                              {"Next object id", Byte},
                                              {"Number of objects", Byte},
                                              {"Objects", DeviceIdObjects}}};

bool addresses_bits(const FunctionInfo& f) noexcept {
    return f.table && is_bit_table(*f.table);
}

}  // namespace

PduLayout request_layout(const FunctionInfo& f) noexcept {
    switch (f.request) {
        case RequestShape::FunctionOnly:
            return {};
        case RequestShape::AddressQuantity:
            return {addresses_bits(f) ? std::span<const PduField>(kReadBits) : kReadRegisters};
        case RequestShape::SingleCoil:
            return {kSingleCoil};
        case RequestShape::SingleRegister:
            return {kSingleRegister};
        case RequestShape::SubFunction:
            return {kSubFunction};
        case RequestShape::MultipleCoils:
            return {kWriteCoils, kAfterCoilWriteHeader};
        case RequestShape::MultipleRegisters:
            return {kWriteRegisters};
        case RequestShape::FileRecords:
            return {f.writes ? std::span<const PduField>(kFileWrite) : kFileRead, kAfterByteCount};
        case RequestShape::MaskWrite:
            return {kMaskWrite};
        case RequestShape::ReadWriteRegisters:
            return {kReadWrite};
        case RequestShape::FifoPointer:
            return {kFifoPointer};
        case RequestShape::MeiTransport:
            return {kMeiRequest};
    }
    return {};
}

PduLayout response_layout(const FunctionInfo& f) noexcept {
    switch (f.response) {
        case ResponseShape::Bits:
            return {kBitsAnswer, kAfterByteCount};
        case ResponseShape::Registers:
            return {kRegistersAnswer, kAfterByteCount};
        case ResponseShape::EchoValue:
            return {addresses_bits(f) ? std::span<const PduField>(kSingleCoil) : kSingleRegister};
        case ResponseShape::EchoQuantity:
            return {kEchoQuantity};
        case ResponseShape::EchoMask:
            return {kMaskWrite};
        case ResponseShape::EchoSubFunction:
            return {kSubFunction};
        case ResponseShape::ExceptionStatus:
            return {kExceptionStatus};
        case ResponseShape::EventCounter:
            return {kEventCounter};
        case ResponseShape::EventLog:
            return {kEventLog};
        case ResponseShape::ServerId:
            return {kServerId};
        case ResponseShape::FileRecords:  // FC 15's answer echoes its request
            return {f.writes ? std::span<const PduField>(kFileWrite) : kFileReadAnswer,
                    kAfterByteCount};
        case ResponseShape::FifoValues:
            return {kFifoAnswer};
        case ResponseShape::MeiObjects:
            return {kMeiAnswer};
    }
    return {};
}

std::size_t fixed_width(FieldKind kind) noexcept {
    switch (kind) {
        case Byte:
        case MeiType:
        case MoreFollows:
            return 1;
        case Word:
        case CoilValue:
            return 2;
        case Registers:
        case PackedBits:
        case Rest:
        case FileSubRequests:
        case FileSubRequestsWithData:
        case FileSubResponses:
        case DeviceIdObjects:
            return 0;
    }
    return 0;
}

}  // namespace mbstorm::codec
