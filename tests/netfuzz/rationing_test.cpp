// Rationing on its own (netfuzz/rationing.hpp): against a device that pauses 500 ms after
// exception 01 or 03 (libmodbus), each kind of request owed one goes out once and later ones
// of a kind one in 32, within a quarter of the run; requests to a unit id the device does not
// answer go one in 16; valid requests always go.
#include "netfuzz/rationing.hpp"

#include <gtest/gtest.h>

#include "netfuzz/finding.hpp"
#include "netfuzz/wire.hpp"

namespace {

using namespace mbstorm::netfuzz;
using Pdu = std::vector<std::uint8_t>;

Case case_of(const Pdu& pdu, std::uint8_t unit = 1) {
    Case c;
    c.steps.push_back(Step{Op::Send, 0, 0, 0, frame_pdu(pdu, 7, unit)});
    return c;
}

struct PausingDevice {
    TargetProfile profile;
    DeviceModel model;
    PausingDevice() {
        profile.probe_pdu = {0x03, 0, 0, 0, 1};
        model.exception_pause_ms[1] = model.exception_pause_ms[3] = 500;
        model.units = {1, 255};
    }
};

const Pdu kQuantityZero = {0x03, 0x00, 0x10, 0x00, 0x00};                // owed 03
const Pdu kValidRead = {0x03, 0x00, 0x10, 0x00, 0x02};                   // owed an answer
const Pdu kByteCountWrong = {0x10, 0x00, 0x10, 0x00, 0x01, 0x04, 0, 1};  // owed 03, another kind

TEST(Rationing, EachKindOwedAPausingExceptionGoesOnceThenOneInThirtyTwo) {
    PausingDevice d;
    Rationing r;
    const double elapsed_s = 1000;  // the pauses' share is far off
    EXPECT_FALSE(r.holds_back(case_of(kQuantityZero), d.profile, d.model, elapsed_s));
    unsigned sent = 0;
    for (int i = 0; i < 64; ++i)
        sent += !r.holds_back(case_of(kQuantityZero), d.profile, d.model, elapsed_s);
    EXPECT_EQ(sent, 2u);
    EXPECT_FALSE(r.holds_back(case_of(kByteCountWrong), d.profile, d.model, elapsed_s))
        << "a kind of its own";
    EXPECT_EQ(r.pause_spent_ms(), 4 * 500u);
    for (int i = 0; i < 100; ++i)
        EXPECT_FALSE(r.holds_back(case_of(kValidRead), d.profile, d.model, elapsed_s));
}

TEST(Rationing, ThePausesStayWithinAQuarterOfTheRun) {
    PausingDevice d;
    Rationing r;
    // 1 s in: 250 ms of pauses allowed; the first 500 ms pause is taken, then none until 2 s.
    EXPECT_FALSE(r.holds_back(case_of(kQuantityZero), d.profile, d.model, 1.0));
    EXPECT_TRUE(r.holds_back(case_of(kByteCountWrong), d.profile, d.model, 1.0));
    EXPECT_FALSE(r.holds_back(case_of(kByteCountWrong), d.profile, d.model, 2.0));
}

TEST(Rationing, ADeviceThatDoesNotPauseGetsEveryInvalidRequest) {
    PausingDevice d;
    d.model.exception_pause_ms = {};
    Rationing r;
    for (int i = 0; i < 50; ++i)
        EXPECT_FALSE(r.holds_back(case_of(kQuantityZero), d.profile, d.model, 1.0));
}

TEST(Rationing, AUnitTheDeviceDoesNotAnswerGetsOneRequestInSixteen) {
    PausingDevice d;
    Rationing r;
    unsigned sent = 0;
    for (int i = 0; i < 64; ++i)
        sent += !r.holds_back(case_of(kValidRead, 7), d.profile, d.model, 1);
    EXPECT_EQ(sent, 4u);
    EXPECT_FALSE(r.holds_back(case_of(kValidRead, 255), d.profile, d.model, 1));
}

}  // namespace
