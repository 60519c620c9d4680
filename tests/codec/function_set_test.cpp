// Lists of function codes ("1-6,15,16"): the one syntax of serve --tls-role and a device
// file's tls_roles, parsed and printed back.
#include <gtest/gtest.h>

#include "codec/function_set.hpp"

namespace mbstorm::codec {
namespace {

TEST(FunctionSet, CodesRangesAndHexParse) {
    FunctionSet set;
    ASSERT_EQ(parse_function_set("1-6,15,0x10,255", set), "");
    EXPECT_EQ(set.count(), 9u);
    EXPECT_TRUE(set.test(1) && set.test(6) && set.test(15) && set.test(16) && set.test(255));
    EXPECT_FALSE(set.test(0) || set.test(7));
    EXPECT_EQ(format_function_set(set), "1-6,15-16,255");
    FunctionSet again;
    ASSERT_EQ(parse_function_set(format_function_set(set), again), "");
    EXPECT_EQ(again, set);
    EXPECT_EQ(format_function_set(FunctionSet{}), "");
}

TEST(FunctionSet, MalformedListsSayWhichItem) {
    for (const char* bad : {"", "0", "256", "6-3", "3,,4", "3,", "x", "1-", "-4", "0x"}) {
        FunctionSet set;
        const std::string why = parse_function_set(bad, set);
        EXPECT_FALSE(why.empty()) << bad;
    }
    FunctionSet set;
    EXPECT_NE(parse_function_set("1,2,300", set).find("'300'"), std::string::npos);
}

}  // namespace
}  // namespace mbstorm::codec
