// The server with a device description: requests routed to per-unit models, unknown units
// answered as a gateway would, and simulated inputs changing over time.
#include <gtest/gtest.h>

#include <memory>

#include "client_test_support.hpp"
#include "server/server.hpp"
#include "slave/data_model.hpp"
#include "slave/device_yaml.hpp"

using namespace mbstorm;
using test::Client;
using test::read_holding;

namespace {

std::uint16_t first_register(const std::vector<std::uint8_t>& rsp) {
    return static_cast<std::uint16_t>(rsp[9] << 8 | rsp[10]);
}

}  // namespace

TEST(ServerDevice, PerUnitModelsAreSeparateAndUnknownUnitsGetGatewayException) {
    const slave::DeviceDescription device = *slave::parse_device_yaml(R"(
units: [1, 2]
init:
  - {table: holding_registers, address: 0, values: [111], units: [1]}
  - {table: holding_registers, address: 0, values: [222], units: [2]}
)");
    auto units = slave::build_units(device);
    auto config = test::test_config();
    config.units = &units;
    server::Server srv(config);
    const Error error = srv.start();
    ASSERT_TRUE(error.ok()) << error.text();
    Client c(srv);
    ASSERT_TRUE(c.send_all(read_holding(1, 1, 0, 1)));
    auto r1 = c.recv_n(test::read_holding_response_size(1));
    ASSERT_EQ(r1.size(), test::read_holding_response_size(1));
    EXPECT_EQ(first_register(r1), 111);
    ASSERT_TRUE(c.send_all(read_holding(2, 2, 0, 1)));
    auto r2 = c.recv_n(test::read_holding_response_size(1));
    ASSERT_EQ(r2.size(), test::read_holding_response_size(1));
    EXPECT_EQ(first_register(r2), 222);
    ASSERT_TRUE(c.send_all(read_holding(3, 9, 0, 1)));
    auto r3 = c.recv_n(9);  // MBAP + 0x83 + code
    ASSERT_EQ(r3.size(), 9u);
    EXPECT_EQ(r3[7], 0x83);
    EXPECT_EQ(r3[8], 0x0B);  // gateway target device failed to respond
}

TEST(ServerDevice, SimulatedInputsChangeWhileServing) {
    const slave::DeviceDescription device = *slave::parse_device_yaml(R"(
simulate:
  - {table: holding_registers, address: 5, wave: ramp, period_ms: 400, amplitude: 1000, offset: 0}
)");
    auto units = slave::build_units(device);
    auto config = test::test_config();
    config.units = &units;
    config.simulated = device.simulated;
    config.simulate_interval_ms = 5;
    server::Server srv(config);
    const Error error = srv.start();
    ASSERT_TRUE(error.ok()) << error.text();
    Client c(srv);
    std::uint16_t first = 0;
    bool changed = false;
    for (int i = 0; i < 200 && !changed; ++i) {
        ASSERT_TRUE(c.send_all(read_holding(static_cast<std::uint16_t>(i), 1, 5, 1)));
        auto r = c.recv_n(test::read_holding_response_size(1));
        ASSERT_EQ(r.size(), test::read_holding_response_size(1));
        if (i == 0)
            first = first_register(r);
        else
            changed = first_register(r) != first;
        usleep(10'000);
    }
    EXPECT_TRUE(changed) << "a ramp input should move within 2 s";
}
