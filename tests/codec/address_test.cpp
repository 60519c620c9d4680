#include "codec/address.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace mbstorm::codec {
namespace {

using testing::HasSubstr;

TEST(AddressRule, PlainNumbersAreProtocolAddresses) {
    AddressRange r;
    EXPECT_EQ(parse_address_range("99", Table::HoldingRegisters, r), "");
    EXPECT_EQ(r.first, 99);
    EXPECT_FALSE(r.reference);
    EXPECT_EQ(parse_address_range("0x9C41", Table::HoldingRegisters, r), "");
    EXPECT_EQ(r.first, 0x9C41);
    EXPECT_EQ(parse_address_range("65535", Table::Coils, r), "");  // 6xxxx: no table digit
    EXPECT_EQ(r.first, 65535);
    EXPECT_EQ(parse_address_range("20000", std::nullopt, r), "");
    EXPECT_EQ(r.first, 20000);
}

TEST(AddressRule, ReferenceNumbersOfTheFunctionsTable) {
    AddressRange r;
    EXPECT_EQ(parse_address_range("40001-40100", Table::HoldingRegisters, r), "");
    EXPECT_EQ(r.first, 0);
    EXPECT_EQ(r.last, 99);
    EXPECT_TRUE(r.is_range);
    EXPECT_TRUE(r.reference);
    EXPECT_EQ(parse_address_range("300010", Table::InputRegisters, r), "");
    EXPECT_EQ(r.first, 9);
    EXPECT_EQ(parse_address_range("00001", Table::Coils, r), "");
    EXPECT_EQ(r.first, 0);
}

TEST(AddressRule, WrongTableNamesTheRightFunctions) {
    AddressRange r;
    EXPECT_THAT(parse_address_range("30001-30010", Table::HoldingRegisters, r),
                HasSubstr("'30001' is an input register reference: read it with 0x04 "
                          "read_input_registers; for protocol address 30001 write 0x7531"));
    EXPECT_THAT(parse_address_range("40001", Table::Coils, r),
                HasSubstr("read it with 0x03 read_holding_registers or 0x17 "
                          "read_write_multiple_registers, write it with 0x06"));
    EXPECT_THAT(parse_address_range("10001", std::nullopt, r),
                HasSubstr("this function addresses no table"));
}

TEST(AddressRule, MalformedInputsSayWhatToWrite) {
    AddressRange r;
    EXPECT_THAT(parse_address_range("40000", Table::HoldingRegisters, r),
                HasSubstr("'40000' is not a valid reference number"));
    EXPECT_THAT(parse_address_range("70000", Table::HoldingRegisters, r),
                HasSubstr("is not an address"));
    EXPECT_THAT(parse_address_range("40001-99", Table::HoldingRegisters, r),
                HasSubstr("mixes a reference number and a protocol address"));
    EXPECT_THAT(parse_address_range("9-3", Table::HoldingRegisters, r),
                HasSubstr("ends before it starts"));
    EXPECT_THAT(parse_address_range("abc", Table::HoldingRegisters, r), HasSubstr("0x hex"));
}

TEST(AddressRule, FormattedAddressesReadBackAsThemselves) {
    for (unsigned a : {0u, 99u, 9999u, 10000u, 20000u, 30000u, 40000u, 49999u, 65535u}) {
        const std::string text = format_protocol_address(static_cast<std::uint16_t>(a));
        AddressRange r;
        ASSERT_EQ(parse_address_range(text, Table::HoldingRegisters, r), "") << text;
        EXPECT_EQ(r.first, a) << text;
    }
    EXPECT_EQ(format_protocol_address(40000), "0x9C40");
    EXPECT_EQ(format_protocol_address(20000), "20000");
}

}  // namespace
}  // namespace mbstorm::codec
