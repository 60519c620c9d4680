#include <gtest/gtest.h>
#include <sys/socket.h>

#include <string>
#include <vector>

#include "net/source_addresses.hpp"

using namespace mbstorm::net;

namespace {

std::vector<std::string> texts(const std::vector<Endpoint>& list) {
    std::vector<std::string> out;
    for (const Endpoint& ep : list) out.push_back(ep.to_string());
    return out;
}

std::string parse_error(std::string_view text) {
    std::vector<Endpoint> list;
    std::string error;
    EXPECT_FALSE(parse_source_addresses(text, list, error)) << text;
    return error;
}

}  // namespace

TEST(SourceAddresses, ListsAndRangesInTheOrderGiven) {
    std::vector<Endpoint> list;
    std::string error;
    ASSERT_TRUE(parse_source_addresses("127.0.0.5, 127.0.0.1-127.0.0.3,::1", list, error)) << error;
    EXPECT_EQ(texts(list), (std::vector<std::string>{"127.0.0.5:0", "127.0.0.1:0", "127.0.0.2:0",
                                                     "127.0.0.3:0", "[::1]:0"}));
    ASSERT_TRUE(parse_source_addresses("127.0.0.254-127.0.1.1", list, error)) << error;
    EXPECT_EQ(list.size(), 4u);
    EXPECT_EQ(list.back().to_string(), "127.0.1.1:0");
    ASSERT_TRUE(parse_source_addresses("[fd00::1]-[fd00::3]", list, error)) << error;
    EXPECT_EQ(texts(list), (std::vector<std::string>{"[fd00::1]:0", "[fd00::2]:0", "[fd00::3]:0"}));
    ASSERT_TRUE(parse_source_addresses("", list, error));
    EXPECT_TRUE(list.empty());
}

TEST(SourceAddresses, BadTextIsRefusedNamingTheEntry) {
    EXPECT_NE(parse_error("127.0.0.x").find("'127.0.0.x' is not a numeric"), std::string::npos);
    EXPECT_NE(parse_error("localhost").find("'localhost'"), std::string::npos);
    EXPECT_NE(parse_error("127.0.0.1,,127.0.0.2").find("empty entry"), std::string::npos);
    EXPECT_NE(parse_error("127.0.0.1-").find("not a range FIRST-LAST"), std::string::npos);
    EXPECT_NE(parse_error("127.0.0.9-127.0.0.2").find("ends before it starts"), std::string::npos);
    EXPECT_NE(parse_error("127.0.0.1-::1").find("mixes IPv4 and IPv6"), std::string::npos);
    EXPECT_NE(parse_error("10.0.0.1-10.1.0.1").find("more than 65536"), std::string::npos);
    EXPECT_NE(parse_error("127.0.0.1:80").find("not a numeric"), std::string::npos);
}

TEST(SourceAddresses, LoopbackIsLocalAndATestNetAddressIsNot) {
    std::vector<Endpoint> list;
    std::string error;
    ASSERT_TRUE(parse_source_addresses("127.0.0.3,192.0.2.77", list, error));
    EXPECT_EQ(check_source_is_local(list[0]), "");
    EXPECT_EQ(check_source_is_local(list[1]),
              "source address 192.0.2.77 is not an address of this machine");
}
