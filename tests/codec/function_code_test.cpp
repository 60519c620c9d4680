// One label and one parser for function codes (issue #12, "Function codes").
#include <gtest/gtest.h>

#include <string>

#include "codec/function_code.hpp"

namespace mbstorm::codec {
namespace {

TEST(FunctionLabel, HexWithPrefixAndName) {
    EXPECT_EQ(function_label(0x10), "0x10 write_multiple_registers");
    EXPECT_EQ(function_label(0x16), "0x16 mask_write_register");
    EXPECT_EQ(function_label(0x03), "0x03 read_holding_registers");
    EXPECT_EQ(function_label(0x2B), "0x2B encapsulated_interface");
}

TEST(FunctionLabel, UnknownCodesAreHexOnly) {
    EXPECT_EQ(function_label(0x41), "0x41");
    EXPECT_EQ(function_label(0x00), "0x00");
    EXPECT_EQ(function_label(0xFF), "0xFF");
}

TEST(ParseFunctionCode, AcceptsNamesHexAndDecimal) {
    struct Case {
        const char* text;
        std::uint8_t fc;
    };
    for (const Case& c :
         {Case{"write_multiple_registers", 0x10}, Case{"0x10", 0x10}, Case{"0X10", 0x10},
          Case{"16", 0x10}, Case{"0x16", 0x16}, Case{"22", 0x16}, Case{"3", 0x03},
          Case{"0x2b", 0x2B}, Case{"0x41", 0x41}, Case{"127", 0x7F}, Case{"0x7F", 0x7F}}) {
        std::uint8_t fc = 0;
        EXPECT_EQ(parse_function_code(c.text, fc), "") << c.text;
        EXPECT_EQ(fc, c.fc) << c.text;
    }
}

TEST(ParseFunctionCode, RefusalNamesTheValueAndTheForms) {
    for (const char* bad : {"", "0", "128", "0x80", "0x", "16h", "-3", "x10", "0x1G",
                            "write_registers", "99999999999999999999", " 3"}) {
        std::uint8_t fc = 0x42;
        const std::string error = parse_function_code(bad, fc);
        ASSERT_FALSE(error.empty()) << bad;
        EXPECT_NE(error.find("'" + std::string(bad) + "'"), std::string::npos) << error;
        EXPECT_NE(error.find(kFunctionCodeForms), std::string::npos) << error;
        EXPECT_EQ(fc, 0x42) << bad;
    }
    std::uint8_t fc = 0;
    EXPECT_NE(parse_function_code("200", fc).find("1..127"), std::string::npos);
}

}  // namespace
}  // namespace mbstorm::codec
