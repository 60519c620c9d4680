// Rationing on its own (netfuzz/rationing.hpp): against a device that pauses 500 ms after
// exception 01 or 03 (libmodbus), each kind of request owed one goes out once, fairest first,
// and later ones of a kind one in 32, within a quarter of the run; requests to a unit id the
// device does not answer go one in 16; valid requests always go.
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

// Whether `c` goes out `elapsed_s` into the run: let through, or kept waiting and released
// before the next round.
bool goes_out(Rationing& r, const Case& c, const PausingDevice& d, double elapsed_s) {
    if (!r.holds_back(c, d.profile, d.model, elapsed_s)) return true;
    for (const Case& out : r.release(elapsed_s))
        if (out.steps[0].bytes == c.steps[0].bytes) return true;
    return false;
}

TEST(Rationing, EachKindOwedAPausingExceptionGoesOnceThenOneInThirtyTwo) {
    PausingDevice d;
    Rationing r;
    const double elapsed_s = 1000;  // the pauses' share is far off
    EXPECT_TRUE(r.holds_back(case_of(kQuantityZero), d.profile, d.model, elapsed_s))
        << "a new kind waits for the next round";
    EXPECT_EQ(r.release(elapsed_s).size(), 1u);
    unsigned sent = 0;
    for (int i = 0; i < 64; ++i) sent += goes_out(r, case_of(kQuantityZero), d, elapsed_s);
    EXPECT_EQ(sent, 2u);
    EXPECT_TRUE(goes_out(r, case_of(kByteCountWrong), d, elapsed_s)) << "a kind of its own";
    EXPECT_EQ(r.pause_spent_ms(), 4 * 500u);
    for (int i = 0; i < 100; ++i)
        EXPECT_FALSE(r.holds_back(case_of(kValidRead), d.profile, d.model, elapsed_s));
}

TEST(Rationing, ThePausesStayWithinAQuarterOfTheRun) {
    PausingDevice d;
    Rationing r;
    // 1 s in: 250 ms of pauses allowed; the first 500 ms pause is taken, then none until 2 s.
    EXPECT_TRUE(goes_out(r, case_of(kQuantityZero), d, 1.0));
    EXPECT_FALSE(goes_out(r, case_of(kByteCountWrong), d, 1.0));
    EXPECT_EQ(r.release(2.0).size(), 1u);
}

// FC 05 with its value wrong, and with its address wrong too (libmodbus answers that 02).
const Pdu kCoilValueWrong = {0x05, 0x00, 0x10, 0x12, 0x34};
const Pdu kCoilValueAndAddressWrong = {0x05, 0x7F, 0x00, 0x12, 0x34};

TEST(Rationing, WaitingKindsGoFairestFirst) {
    PausingDevice d;
    d.model.table(mbstorm::codec::Table::Coils).ranges = {{0, 999}};
    d.model.table(mbstorm::codec::Table::HoldingRegisters).ranges = {{0, 999}};
    Rationing r;
    EXPECT_TRUE(goes_out(r, case_of(kQuantityZero), d, 0.0));
    // The share is spent: the kinds that come now wait.
    const Pdu fc03_address = {0x03, 0x7F, 0x00, 0x00, 0x00};
    EXPECT_TRUE(r.holds_back(case_of(kByteCountWrong), d.profile, d.model, 0.5));
    EXPECT_TRUE(r.holds_back(case_of(fc03_address), d.profile, d.model, 0.5));
    EXPECT_TRUE(r.holds_back(case_of(kCoilValueAndAddressWrong), d.profile, d.model, 0.5));
    EXPECT_TRUE(r.holds_back(case_of(kCoilValueWrong), d.profile, d.model, 0.5));
    EXPECT_TRUE(r.holds_back(case_of(kCoilValueWrong), d.profile, d.model, 0.5));
    EXPECT_EQ(r.waiting(), 4u) << "each waiting kind is kept once";
    EXPECT_TRUE(r.release(1.0).empty()) << "250 ms of pauses allowed, 500 spent";
    // 2 s in: one more pause. FC 03 has a kind sent already, FC 10 and FC 05 none: FC 05's
    // with one wrong field goes before FC 10's with two (its byte count and data length).
    std::vector<Case> out = r.release(2.0);
    ASSERT_EQ(out.size(), 1u);
    EXPECT_EQ(out[0].steps[0].bytes, case_of(kCoilValueWrong).steps[0].bytes);
    // Then FC 10's, before the second kinds of FC 03 and FC 05, in the order they came.
    out = r.release(4.0);
    ASSERT_EQ(out.size(), 1u);
    EXPECT_EQ(out[0].steps[0].bytes[7], 0x10);
    out = r.release(8.0);
    ASSERT_EQ(out.size(), 2u);
    EXPECT_EQ(out[0].steps[0].bytes[7], 0x03);
    EXPECT_EQ(out[1].steps[0].bytes, case_of(kCoilValueAndAddressWrong).steps[0].bytes);
    EXPECT_EQ(r.waiting(), 0u);
    EXPECT_EQ(r.pause_spent_ms(), 5 * 500u);
}

TEST(Rationing, ALengthThatDisagreesWithTheFieldsIsOneKindThatGoesAfterTheFieldKinds) {
    PausingDevice d;
    d.model.table(mbstorm::codec::Table::HoldingRegisters).ranges = {{0, 999}};
    Rationing r;
    const Pdu truncated = {0x03, 0x00, 0x10};
    const Pdu trailing = {0x03, 0x00, 0x10, 0x00, 0x01, 0xAA};
    EXPECT_TRUE(r.holds_back(case_of(truncated), d.profile, d.model, 0.0));
    EXPECT_TRUE(r.holds_back(case_of({0x03, 0x7F, 0x00, 0x00}), d.profile, d.model, 0.0));
    EXPECT_TRUE(r.holds_back(case_of(trailing), d.profile, d.model, 0.0));
    EXPECT_TRUE(r.holds_back(case_of(kQuantityZero), d.profile, d.model, 0.0));
    EXPECT_EQ(r.waiting(), 3u) << "truncated (twice), trailing bytes, quantity";
    const std::vector<Case> out = r.release(0.0);
    ASSERT_EQ(out.size(), 1u);
    EXPECT_EQ(out[0].steps[0].bytes, case_of(kQuantityZero).steps[0].bytes);
}

TEST(Rationing, AByteCountTooLargeAndOneTooSmallAreTwoKinds) {
    // libmodbus 3.1.6 refuses FC 0F's byte count when it is too small, not when too large.
    PausingDevice d;
    d.model.table(mbstorm::codec::Table::Coils).ranges = {{0, 999}};
    Rationing r;
    const Pdu too_small = {0x0F, 0x00, 0x10, 0x00, 0x10, 0x01, 0xFF};
    const Pdu too_large = {0x0F, 0x00, 0x10, 0x00, 0x10, 0x03, 0xFF, 0xFF, 0xFF};
    EXPECT_TRUE(goes_out(r, case_of(too_small), d, 1000.0));
    EXPECT_TRUE(goes_out(r, case_of(too_large), d, 1000.0));
}

TEST(Rationing, AKindSentAgainWaitsBehindEveryNewKind) {
    PausingDevice d;
    Rationing r;
    EXPECT_TRUE(goes_out(r, case_of(kQuantityZero), d, 0.0));
    EXPECT_TRUE(r.holds_back(case_of(kByteCountWrong), d.profile, d.model, 0.5));
    unsigned sent = 0;
    for (int i = 0; i < 64; ++i)
        sent += !r.holds_back(case_of(kQuantityZero), d.profile, d.model, 1000.0);
    EXPECT_EQ(sent, 0u) << "a new kind is waiting";
}

TEST(Rationing, ARoundThatTookLessThanItsPausesGivesTheRestBack) {
    PausingDevice d;
    d.model.table(mbstorm::codec::Table::Coils).ranges = {{0, 999}};
    Rationing r;
    EXPECT_TRUE(goes_out(r, case_of(kCoilValueAndAddressWrong), d, 0.0));
    EXPECT_EQ(r.pause_spent_ms(), 500u);
    r.round_took(3.0);  // answered 02 at once: no pause
    EXPECT_EQ(r.pause_spent_ms(), 3u);
    EXPECT_TRUE(goes_out(r, case_of(kCoilValueWrong), d, 0.1));
    r.round_took(502.0);  // the pause came
    EXPECT_EQ(r.pause_spent_ms(), 503u);
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
