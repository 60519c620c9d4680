// The scenario's `transport:` key (tcp, rtu-over-tcp): parsed into the plan's framing, printed
// back, refused when unknown, and --transport overriding it.
#include <gtest/gtest.h>

#include "scenario/print.hpp"
#include "scenario/scenario.hpp"

namespace mbstorm::scenario {
namespace {

TEST(ScenarioTransport, RtuOverTcpSetsTheFramingAndPrintsBack) {
    const Scenario s = parse_scenario(
        "target: 127.0.0.1:1502\ntransport: rtu-over-tcp\noperations: [{function: 3}]\n", "t.yaml");
    EXPECT_EQ(s.plan.framing, codec::Framing::Rtu);
    const std::string printed = format_scenario(s);
    EXPECT_NE(printed.find("transport: rtu-over-tcp"), std::string::npos) << printed;
    EXPECT_EQ(parse_scenario(printed, "again.yaml").plan.framing, codec::Framing::Rtu);
}

TEST(ScenarioTransport, DefaultAndExplicitTcpAreMbap) {
    EXPECT_EQ(parse_scenario("operations: [{function: 3}]\n", "a.yaml").plan.framing,
              codec::Framing::Mbap);
    EXPECT_EQ(
        parse_scenario("transport: tcp\noperations: [{function: 3}]\n", "b.yaml").plan.framing,
        codec::Framing::Mbap);
}

TEST(ScenarioTransport, UnknownValueIsRefusedWithTheChoices) {
    try {
        parse_scenario("transport: udp\noperations: [{function: 3}]\n", "c.yaml");
        FAIL() << "accepted transport: udp";
    } catch (const ScenarioError& e) {
        EXPECT_NE(std::string(e.what()).find("tcp, rtu-over-tcp"), std::string::npos) << e.what();
    }
}

TEST(ScenarioTransport, RtuRunsOneRequestAtATimeUnlessDepthIsGiven) {
    EXPECT_EQ(parse_scenario("transport: rtu-over-tcp\noperations: [{function: 3}]\n", "d.yaml")
                  .plan.depth,
              1u);
    try {
        parse_scenario("transport: rtu-over-tcp\ndepth: 8\noperations: [{function: 3}]\n",
                       "e.yaml");
        FAIL() << "accepted depth 8 with RTU over TCP";
    } catch (const ScenarioError& e) {
        EXPECT_NE(std::string(e.what()).find("RTU over TCP"), std::string::npos) << e.what();
    }
    // --transport on the command line: depth 1 unless --depth is given too.
    Scenario s = parse_scenario("depth: 8\noperations: [{function: 3}]\n", "f.yaml");
    Overrides o;
    o.framing = codec::Framing::Rtu;
    EXPECT_TRUE(apply_overrides(s, o).empty());
    EXPECT_EQ(s.plan.framing, codec::Framing::Rtu);
    EXPECT_EQ(s.plan.depth, 1u);
    Scenario t = parse_scenario("operations: [{function: 3}]\n", "g.yaml");
    o.depth = 4;
    const auto problems = apply_overrides(t, o);
    ASSERT_FALSE(problems.empty());
    EXPECT_NE(problems[0].find("RTU over TCP"), std::string::npos) << problems[0];
}

}  // namespace
}  // namespace mbstorm::scenario
