#include "load/write_safety.hpp"

#include <gtest/gtest.h>

namespace mbstorm::load {
namespace {

TEST(Loopback, RecognisesLoopbackAddresses) {
    EXPECT_TRUE(is_loopback_address("127.0.0.1"));
    EXPECT_TRUE(is_loopback_address("127.255.3.4"));
    EXPECT_TRUE(is_loopback_address("::1"));
    EXPECT_TRUE(is_loopback_address("[::1]"));
    EXPECT_TRUE(is_loopback_address("::ffff:127.0.0.1"));
    EXPECT_FALSE(is_loopback_address("128.0.0.1"));
    EXPECT_FALSE(is_loopback_address("10.0.0.1"));
    EXPECT_FALSE(is_loopback_address("::2"));
    EXPECT_FALSE(is_loopback_address("localhost"));  // names are not trusted: fail safe
    EXPECT_FALSE(is_loopback_address(""));
}

std::vector<Operation> mix() {
    Operation read;
    read.name = "poll";
    read.function = 0x03;
    Operation write;
    write.name = "setpoint";
    write.function = 0x10;
    Operation coil;
    coil.function = 0x05;
    return {read, write, coil};
}

TEST(WriteSafety, RefusesWritesToANonLoopbackTargetAndNamesThem) {
    const auto verdict = check_write_safety(mix(), "192.168.1.10", false);
    EXPECT_FALSE(verdict.allowed());
    EXPECT_EQ(verdict.refusal.code(), ErrorCode::Refused);
    ASSERT_EQ(verdict.write_operations.size(), 2u);
    EXPECT_NE(verdict.refusal.message().find("setpoint"), std::string::npos);
    EXPECT_NE(verdict.refusal.message().find("0x05"), std::string::npos);
    EXPECT_NE(verdict.refusal.message().find("192.168.1.10"), std::string::npos);
    EXPECT_EQ(verdict.refusal.message().find("poll"), std::string::npos);
}

TEST(WriteSafety, AllowsWritesToLoopbackOrWithAllowWrites) {
    EXPECT_TRUE(check_write_safety(mix(), "127.0.0.1", false).allowed());
    EXPECT_TRUE(check_write_safety(mix(), "::1", false).allowed());
    EXPECT_TRUE(check_write_safety(mix(), "192.168.1.10", true).allowed());
}

TEST(WriteSafety, ReadsAreAlwaysAllowed) {
    Operation read;
    read.function = 0x04;
    EXPECT_TRUE(check_write_safety({read}, "8.8.8.8", false).allowed());
}

TEST(WriteSafety, EveryWriteFunctionCodeIsCaught) {
    for (std::uint8_t fc : {0x05, 0x06, 0x08, 0x0F, 0x10, 0x15, 0x16, 0x17}) {
        Operation op;
        op.function = fc;
        EXPECT_FALSE(check_write_safety({op}, "10.1.2.3", false).allowed()) << int(fc);
    }
}

}  // namespace
}  // namespace mbstorm::load
