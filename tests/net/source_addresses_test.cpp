#include <gtest/gtest.h>
#include <sys/socket.h>

#include <string>
#include <vector>

#include "net/source_addresses.hpp"

using namespace mbstorm::net;
using mbstorm::Error;
using mbstorm::ErrorCode;
using mbstorm::Result;

namespace {

std::vector<std::string> texts(const std::vector<Endpoint>& list) {
    std::vector<std::string> out;
    for (const Endpoint& ep : list) out.push_back(ep.to_string());
    return out;
}

std::string parse_error(std::string_view text) {
    const Result<std::vector<Endpoint>> list = parse_source_addresses(text);
    EXPECT_EQ(list.error().code(), ErrorCode::InvalidInput) << text;
    return list.error().text();
}

std::vector<Endpoint> parsed(std::string_view text) {
    Result<std::vector<Endpoint>> list = parse_source_addresses(text);
    EXPECT_TRUE(list.ok()) << list.error().text();
    return list.ok() ? std::move(list).value() : std::vector<Endpoint>{};
}

}  // namespace

TEST(SourceAddresses, ListsAndRangesInTheOrderGiven) {
    std::vector<Endpoint> list = parsed("127.0.0.5, 127.0.0.1-127.0.0.3,::1");
    EXPECT_EQ(texts(list), (std::vector<std::string>{"127.0.0.5:0", "127.0.0.1:0", "127.0.0.2:0",
                                                     "127.0.0.3:0", "[::1]:0"}));
    list = parsed("127.0.0.254-127.0.1.1");
    ASSERT_EQ(list.size(), 4u);
    EXPECT_EQ(list.back().to_string(), "127.0.1.1:0");
    list = parsed("[fd00::1]-[fd00::3]");
    EXPECT_EQ(texts(list), (std::vector<std::string>{"[fd00::1]:0", "[fd00::2]:0", "[fd00::3]:0"}));
    EXPECT_TRUE(parsed("").empty());
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
    const std::vector<Endpoint> list = parsed("127.0.0.3,192.0.2.77");
    ASSERT_EQ(list.size(), 2u);
    EXPECT_TRUE(check_source_is_local(list[0]).ok());
    const Error foreign = check_source_is_local(list[1]);
    EXPECT_EQ(foreign.code(), ErrorCode::NotFound);
    EXPECT_EQ(foreign.text(), "source address 192.0.2.77 is not an address of this machine");
}
