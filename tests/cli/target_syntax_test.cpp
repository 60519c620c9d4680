// One target syntax for every subcommand: HOST, HOST:PORT, [IPv6]:PORT or a bare IPv6 address,
// port 502 when omitted. Nothing listens on 502 here, so each run names the address it tried.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "../support/run_mbstorm.hpp"

using mbstorm::test::run_mbstorm;
using testing::HasSubstr;
using testing::Not;

namespace {

TEST(TargetSyntax, RunDefaultsToPort502) {
    struct Case {
        const char* target;
        const char* endpoint;
    };
    for (const Case& c : {Case{"127.0.0.1", "127.0.0.1:502"}, Case{"::1", "[::1]:502"},
                          Case{"[::1]", "[::1]:502"}}) {
        auto r = run_mbstorm(
            std::string("run -q -d 1s --connect-timeout 500ms --target ") + c.target, 60);
        EXPECT_EQ(r.exit_code, 2) << c.target << "\n" << r.output;
        EXPECT_THAT(r.output, HasSubstr(c.endpoint)) << c.target << "\n" << r.output;
        EXPECT_THAT(r.output, Not(HasSubstr("needs a port"))) << r.output;
    }
}

// fuzz (and replay, which resolves its target the same way) took only 127.0.0.0/8 and ::1 for
// loopback, while run and write also take the IPv4-mapped ::ffff:127.x (issue #31): one rule.
TEST(TargetSyntax, FuzzTakesLoopbackAsRunAndWriteDo) {
    auto mapped =
        run_mbstorm("fuzz -q --seconds 1 --timeout 200ms --target [::ffff:127.0.0.1]:1", 60);
    EXPECT_THAT(mapped.output, Not(HasSubstr("not a loopback address"))) << mapped.output;
    EXPECT_THAT(mapped.output, HasSubstr("cannot connect")) << mapped.output;
    auto remote = run_mbstorm("fuzz -q --seconds 1 --target [::ffff:10.0.0.1]:1", 60);
    EXPECT_EQ(remote.exit_code, 2) << remote.output;
    EXPECT_THAT(remote.output, HasSubstr("is not a loopback address")) << remote.output;
}

TEST(TargetSyntax, ScenarioTargetTakesTheSameSyntax) {
    auto r = run_mbstorm(
        "run --print-scenario --target ::1 " MBSTORM_SOURCE_DIR "/scenarios/quickstart.yaml", 30);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_THAT(r.output, HasSubstr("::1")) << r.output;
}

TEST(TargetSyntax, FuzzDefaultsToPort502) {
    for (const char* target : {"127.0.0.1", "::1", "[::1]"}) {
        auto r =
            run_mbstorm(std::string("fuzz -q --cases 5 --timeout 200ms --target ") + target, 60);
        EXPECT_EQ(r.exit_code, 2) << target << "\n" << r.output;
        EXPECT_THAT(r.output, HasSubstr(":502")) << target << "\n" << r.output;
    }
}

TEST(TargetSyntax, BadTargetsNameTheForms) {
    auto r = run_mbstorm("run -q -d 1s --target 127.0.0.1:", 30);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_THAT(r.output, HasSubstr("port 502 if omitted")) << r.output;
}

}  // namespace
