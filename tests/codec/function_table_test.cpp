// The function-code descriptor table: the one place other layers learn function facts from.
#include <gtest/gtest.h>

#include <array>
#include <set>

#include "codec/address.hpp"
#include "codec/function_code.hpp"
#include "codec/pdu.hpp"

namespace mbstorm::codec {
namespace {

TEST(FunctionTable, CodesAreInOrderAndMatchTheDescriptors) {
    const auto functions = public_functions();
    const auto codes = public_function_codes();
    ASSERT_EQ(functions.size(), codes.size());
    for (std::size_t i = 0; i < codes.size(); ++i) {
        EXPECT_EQ(codes[i], to_byte(functions[i].code));
        if (i > 0) {
            EXPECT_LT(codes[i - 1], codes[i]);
        }
        EXPECT_EQ(function_info(codes[i]), &functions[i]);
        EXPECT_EQ(function_name(codes[i]), functions[i].name);
        EXPECT_EQ(is_write_function(codes[i]), functions[i].writes);
    }
    int known = 0;
    for (int fc = 0; fc < 256; ++fc) {
        const auto b = static_cast<std::uint8_t>(fc);
        if (function_info(b) != nullptr) ++known;
        EXPECT_EQ(function_info(b) != nullptr, is_supported_function(b));
    }
    EXPECT_EQ(known, static_cast<int>(codes.size()));
}

TEST(FunctionTable, QuantityLimitsAndTablesAreTheSpecifications) {
    EXPECT_EQ(quantity_range(0x01).max, limits::kMaxReadBits);
    EXPECT_EQ(quantity_range(0x03).max, limits::kMaxReadRegisters);
    EXPECT_EQ(quantity_range(0x0F).max, limits::kMaxWriteCoils);
    EXPECT_EQ(quantity_range(0x10).max, limits::kMaxWriteRegisters);
    EXPECT_EQ(quantity_range(0x17).max, limits::kMaxRwReadRegisters);
    EXPECT_EQ(quantity_range(0x06).max, 1);
    EXPECT_EQ(quantity_range(0x18).max, 0);
    EXPECT_EQ(quantity_range(0x41).max, 0);
    EXPECT_EQ(function_table(0x05), Table::Coils);
    EXPECT_EQ(function_table(0x02), Table::DiscreteInputs);
    EXPECT_EQ(function_table(0x04), Table::InputRegisters);
    EXPECT_EQ(function_table(0x18), Table::HoldingRegisters);
    EXPECT_EQ(function_table(0x11), std::nullopt);
    EXPECT_TRUE(request_is(0x17, RequestShape::ReadWriteRegisters));
    EXPECT_TRUE(response_is(0x17, ResponseShape::Registers));
    EXPECT_FALSE(request_is(0x41, RequestShape::FunctionOnly));
}

// `read` and `encode --ref` pick the read of a table, `write` its single and multiple writes.
TEST(FunctionTable, FunctionForATableAndAShape) {
    EXPECT_EQ(function_for(Table::Coils, RequestShape::AddressQuantity), 0x01);
    EXPECT_EQ(function_for(Table::DiscreteInputs, RequestShape::AddressQuantity), 0x02);
    EXPECT_EQ(function_for(Table::HoldingRegisters, RequestShape::AddressQuantity), 0x03);
    EXPECT_EQ(function_for(Table::InputRegisters, RequestShape::AddressQuantity), 0x04);
    EXPECT_EQ(function_for(Table::Coils, RequestShape::SingleCoil), 0x05);
    EXPECT_EQ(function_for(Table::HoldingRegisters, RequestShape::SingleRegister), 0x06);
    EXPECT_EQ(function_for(Table::Coils, RequestShape::MultipleCoils), 0x0F);
    EXPECT_EQ(function_for(Table::HoldingRegisters, RequestShape::MultipleRegisters), 0x10);
    EXPECT_EQ(function_for(Table::InputRegisters, RequestShape::SingleRegister), 0);
}

// request_pdu_size() is what the load engine sizes its buffers by: it must equal what the
// encoder writes for every shape a generator fills.
TEST(FunctionTable, RequestSizeIsWhatTheEncoderWrites) {
    std::array<std::uint8_t, limits::kMaxPdu> data{};
    std::array<std::uint8_t, limits::kMaxPdu> out{};
    for (const FunctionInfo& f : public_functions()) {
        if (f.request == RequestShape::FileRecords) continue;
        Request r;
        r.function = to_byte(f.code);
        r.quantity = f.quantity.max != 0 ? f.quantity.max : 0;
        r.write_quantity = f.request == RequestShape::ReadWriteRegisters ? 3 : 0;
        r.value = limits::kCoilOn;
        r.mei_type = kMeiReadDeviceId;
        r.device_id_code = 1;
        if (f.request == RequestShape::MultipleCoils) r.payload = Bytes(data.data(), 246);
        if (f.request == RequestShape::MultipleRegisters) r.payload = Bytes(data.data(), 246);
        if (f.request == RequestShape::ReadWriteRegisters) r.payload = Bytes(data.data(), 6);
        if (f.request == RequestShape::SubFunction) r.payload = Bytes(data.data(), 2);
        const EncodeResult written = encode_request(r, out);
        ASSERT_TRUE(written.ok()) << f.name;
        EXPECT_EQ(written.size, request_pdu_size(r.function, r.quantity, r.write_quantity))
            << f.name;
    }
    EXPECT_EQ(request_pdu_size(0x14, 0, 0), limits::kMaxPdu);
    EXPECT_EQ(request_pdu_size(0x41, 0, 0), limits::kMaxPdu);
}

}  // namespace
}  // namespace mbstorm::codec
