// The Modbus/TCP Security role allow-list: --tls-role ROLE=FC,FC-FC,... rules.
#include <gtest/gtest.h>

#include <string>

#include "server/tls_roles.hpp"

namespace mbstorm::server {
namespace {

TEST(TlsRoles, NoRulesAllowEveryRoleEverything) {
    TlsRoles roles;
    EXPECT_TRUE(roles.empty());
    EXPECT_EQ(roles.allowed_for("Operator"), nullptr);
    EXPECT_EQ(roles.allowed_for(""), nullptr);
}

TEST(TlsRoles, RulesListCodesAndRangesPerRole) {
    TlsRoles roles;
    ASSERT_TRUE(roles.add_rule("Operator=1-6,15,0x10").ok());
    ASSERT_TRUE(roles.add_rule("Viewer=3").ok());
    ASSERT_TRUE(roles.add_rule("Viewer=4").ok());  // a role's rules add up
    const FunctionSet* op = roles.allowed_for("Operator");
    ASSERT_NE(op, nullptr);
    for (unsigned fc : {1u, 2u, 3u, 4u, 5u, 6u, 15u, 16u}) EXPECT_TRUE(op->test(fc)) << fc;
    for (unsigned fc : {7u, 8u, 17u, 23u}) EXPECT_FALSE(op->test(fc)) << fc;
    const FunctionSet* viewer = roles.allowed_for("Viewer");
    ASSERT_NE(viewer, nullptr);
    EXPECT_EQ(viewer->count(), 2u);
    // A role no rule names may use nothing once any rule is given.
    const FunctionSet* other = roles.allowed_for("Guest");
    ASSERT_NE(other, nullptr);
    EXPECT_TRUE(other->none());
}

TEST(TlsRoles, MalformedRulesAreRefusedWithAReason) {
    for (const char* bad : {"Operator", "=3", "Operator=", "Operator=0", "Operator=256",
                            "Operator=6-3", "Operator=3,,4", "Operator=x"}) {
        TlsRoles roles;
        const Error error = roles.add_rule(bad);
        EXPECT_EQ(error.code(), ErrorCode::InvalidInput) << bad;
        EXPECT_FALSE(error.message().empty()) << bad;
    }
}

}  // namespace
}  // namespace mbstorm::server
