// Shared and per-unit models, unknown units, unit-0 broadcast.
#include <gtest/gtest.h>

#include "slave_test_support.hpp"

namespace mbstorm::slave::test {
namespace {

using codec::ExceptionCode;

TEST(UnitModels, SharedModeServesEveryUnitFromOneModel) {
    const UnitModels units = UnitModels::shared(small_config());
    EXPECT_TRUE(units.is_shared());
    EXPECT_EQ(units.model_count(), 1u);
    EXPECT_EQ(units.find(0), units.find(255));
    call(units, 7, Pdu(0x06).u16(3).u16(0x77));
    EXPECT_EQ(call(units, 200, Pdu(0x03).u16(3).u16(1)).reg(0), 0x77);
    // Unit 0 is an ordinary address over TCP by default.
    EXPECT_EQ(call(units, 0, Pdu(0x03).u16(3).u16(1)).reg(0), 0x77);
}

TEST(UnitModels, PerUnitModelsAreIndependent) {
    const std::uint8_t ids[] = {1, 2, 2, 9};
    const UnitModels units = UnitModels::per_unit(small_config(), ids);
    EXPECT_EQ(units.model_count(), 3u);
    EXPECT_EQ(units.units(), (std::vector<std::uint8_t>{1, 2, 9}));
    call(units, 1, Pdu(0x06).u16(0).u16(111));
    call(units, 2, Pdu(0x06).u16(0).u16(222));
    EXPECT_EQ(call(units, 1, Pdu(0x03).u16(0).u16(1)).reg(0), 111);
    EXPECT_EQ(call(units, 2, Pdu(0x03).u16(0).u16(1)).reg(0), 222);
    EXPECT_EQ(call(units, 9, Pdu(0x03).u16(0).u16(1)).reg(0), 0);
    EXPECT_EQ(units.find(3), nullptr);
}

TEST(UnitModels, UnknownUnitPolicies) {
    const std::uint8_t ids[] = {1};
    UnitModels units = UnitModels::per_unit(small_config(), ids);
    EXPECT_TRUE(call(units, 5, Pdu(0x03).u16(0).u16(1))
                    .is_exception(ExceptionCode::GatewayTargetFailedToRespond));
    units.unknown_unit_policy = UnknownUnitPolicy::GatewayPathUnavailable;
    EXPECT_TRUE(call(units, 5, Pdu(0x03).u16(0).u16(1))
                    .is_exception(ExceptionCode::GatewayPathUnavailable));
    units.unknown_unit_policy = UnknownUnitPolicy::Ignore;
    EXPECT_EQ(call(units, 5, Pdu(0x03).u16(0).u16(1)).result.outcome, Outcome::NoResponse);
}

TEST(UnitModels, BroadcastWritesEveryModelAndNeverAnswers) {
    const std::uint8_t ids[] = {1, 2};
    UnitModels units = UnitModels::per_unit(small_config(), ids);
    units.broadcast_unit_zero = true;
    const Reply w = call(units, 0, Pdu(0x06).u16(4).u16(0x4444));
    EXPECT_EQ(w.result.outcome, Outcome::NoResponse);
    EXPECT_TRUE(w.result.wrote);
    EXPECT_EQ(units.find(1)->holding_registers().get(4), 0x4444);
    EXPECT_EQ(units.find(2)->holding_registers().get(4), 0x4444);
    // Reads are not executed, still no answer; both count as "no response".
    EXPECT_EQ(call(units, 0, Pdu(0x03).u16(4).u16(1)).result.outcome, Outcome::NoResponse);
    EXPECT_EQ(units.find(1)->diagnostics().no_response_count(), 2);
}

TEST(UnitModels, DiagnosticsArePerModel) {
    const std::uint8_t ids[] = {1, 2};
    const UnitModels units = UnitModels::per_unit(small_config(), ids);
    call(units, 1, Pdu(0x03).u16(0).u16(1));
    call(units, 1, Pdu(0x03).u16(0).u16(1));
    EXPECT_EQ(units.find(1)->diagnostics().message_count(), 2);
    EXPECT_EQ(units.find(2)->diagnostics().message_count(), 0);
}

}  // namespace
}  // namespace mbstorm::slave::test
