// The field layouts `decode` walks agree with what the encoder and the descriptor table say
// about the same bytes, so a layout cannot drift from the codec it describes.
#include <gtest/gtest.h>

#include <string>

#include "codec/function_code.hpp"
#include "codec/pdu.hpp"
#include "codec/pdu_layout.hpp"

namespace mbstorm::codec {
namespace {

// The field starting at PDU offset `at` (the function code is offset 0); nullptr when the
// fixed fields before it do not reach it exactly.
const PduField* field_at(const PduLayout& layout, std::size_t at) {
    std::size_t offset = 1;
    for (const PduField& f : layout.fields) {
        if (offset == at) return &f;
        const std::size_t width = fixed_width(f.kind);
        if (width == 0) return nullptr;
        offset += width;
    }
    return nullptr;
}

// 1 + the widths of all fields, or 0 when a field's width depends on the PDU.
std::size_t fixed_size(const PduLayout& layout) {
    std::size_t size = 1;
    for (const PduField& f : layout.fields) {
        if (fixed_width(f.kind) == 0) return 0;
        size += fixed_width(f.kind);
    }
    return size;
}

TEST(PduLayout, FixedRequestLayoutsAreAsLongAsTheEncodersRequests) {
    for (const FunctionInfo& f : public_functions()) {
        const std::size_t size = fixed_size(request_layout(f));
        if (size == 0) continue;
        EXPECT_EQ(size, request_pdu_size(to_byte(f.code), 1, 1)) << f.name;
    }
}

TEST(PduLayout, AddressFieldsAreWhereTheTableSaysTheyAre) {
    for (const FunctionInfo& f : public_functions()) {
        const AddressFields at = address_fields(f.request);
        for (std::size_t offset : {at.first, at.second}) {
            if (offset == 0) continue;
            const PduField* field = field_at(request_layout(f), offset);
            ASSERT_NE(field, nullptr) << f.name << " offset " << offset;
            EXPECT_EQ(field->kind, FieldKind::Word) << f.name;
            EXPECT_NE(std::string(field->name).find("address"), std::string::npos) << f.name;
        }
    }
}

TEST(PduLayout, CountFieldsAreWhereTheTableSaysTheyAre) {
    for (const FunctionInfo& f : public_functions()) {
        const RequestFields at = request_fields(to_byte(f.code));
        for (std::size_t offset : {at.quantity, at.written}) {
            if (offset == 0) continue;
            const PduField* field = field_at(request_layout(f), offset);
            ASSERT_NE(field, nullptr) << f.name << " offset " << offset;
            EXPECT_NE(std::string(field->name).find("Quantity"), std::string::npos) << f.name;
        }
        if (at.byte_count != 0) {
            const PduField* field = field_at(request_layout(f), at.byte_count);
            ASSERT_NE(field, nullptr) << f.name;
            EXPECT_EQ(field->kind, FieldKind::Byte) << f.name;
        }
    }
}

// A refused PDU is read from the bytes at payload_at: there the decoder's payload begins too.
TEST(PduLayout, PayloadStartsWhereTheDecoderPutsIt) {
    const std::uint8_t write_coils[] = {0x0F, 0x00, 0x13, 0x00, 0x0A, 0x02, 0xCD, 0x01};
    const std::uint8_t read_registers_answer[] = {0x03, 0x04, 0x00, 0x0A, 0x00, 0x0B};
    Request req;
    ASSERT_TRUE(decode_request(write_coils, req).ok());
    EXPECT_EQ(req.payload.data(), write_coils + request_layout(*function_info(0x0F)).payload_at);
    Response rsp;
    ASSERT_EQ(decode_response(read_registers_answer, rsp), CodecError::Ok);
    EXPECT_EQ(rsp.payload.data(),
              read_registers_answer + response_layout(*function_info(0x03)).payload_at);
}

}  // namespace
}  // namespace mbstorm::codec
