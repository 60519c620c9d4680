// The scenario's `transport:` key (tcp, rtu-over-tcp): parsed into the plan's framing, printed
// back, refused when unknown, and --transport overriding it.
#include <gtest/gtest.h>

#include "must_parse.hpp"
#include "scenario/print.hpp"
#include "scenario/scenario.hpp"

namespace mbstorm::scenario {
namespace {

TEST(ScenarioTransport, RtuOverTcpSetsTheFramingAndPrintsBack) {
    const Scenario s = must_parse(
        "target: 127.0.0.1:1502\ntransport: rtu-over-tcp\noperations: [{function: 3}]\n", "t.yaml");
    EXPECT_EQ(s.plan.framing, codec::Framing::Rtu);
    const std::string printed = format_scenario(s);
    EXPECT_NE(printed.find("transport: rtu-over-tcp"), std::string::npos) << printed;
    EXPECT_EQ(must_parse(printed, "again.yaml").plan.framing, codec::Framing::Rtu);
}

TEST(ScenarioTransport, DefaultAndExplicitTcpAreMbap) {
    EXPECT_EQ(must_parse("operations: [{function: 3}]\n", "a.yaml").plan.framing,
              codec::Framing::Mbap);
    EXPECT_EQ(must_parse("transport: tcp\noperations: [{function: 3}]\n", "b.yaml").plan.framing,
              codec::Framing::Mbap);
}

TEST(ScenarioTransport, UnknownValueIsRefusedWithTheChoices) {
    const Error e =
        parse_scenario("transport: udp\noperations: [{function: 3}]\n", "c.yaml").error();
    ASSERT_FALSE(e.ok()) << "accepted transport: udp";
    EXPECT_NE(e.text().find("tcp, rtu-over-tcp"), std::string::npos) << e.text();
}

TEST(ScenarioTransport, RtuRunsOneRequestAtATimeUnlessDepthIsGiven) {
    EXPECT_EQ(
        must_parse("transport: rtu-over-tcp\noperations: [{function: 3}]\n", "d.yaml").plan.depth,
        1u);
    const Error e =
        parse_scenario("transport: rtu-over-tcp\ndepth: 8\noperations: [{function: 3}]\n", "e.yaml")
            .error();
    ASSERT_FALSE(e.ok()) << "accepted depth 8 with RTU over TCP";
    EXPECT_NE(e.text().find("RTU over TCP"), std::string::npos) << e.text();
    // --transport on the command line: depth 1 unless --depth is given too.
    Scenario s = must_parse("depth: 8\noperations: [{function: 3}]\n", "f.yaml");
    Overrides o;
    o.framing = codec::Framing::Rtu;
    EXPECT_TRUE(apply_overrides(s, o).ok());
    EXPECT_EQ(s.plan.framing, codec::Framing::Rtu);
    EXPECT_EQ(s.plan.depth, 1u);
    Scenario t = must_parse("operations: [{function: 3}]\n", "g.yaml");
    o.depth = 4;
    const Error problems = apply_overrides(t, o);
    ASSERT_FALSE(problems.ok());
    EXPECT_NE(problems.message().find("RTU over TCP"), std::string::npos) << problems.text();
}

}  // namespace
}  // namespace mbstorm::scenario
