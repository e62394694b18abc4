// RIM state machine, fans, CPU temperature, wiring faults and their propagation through the
// exception tree (guide §3, Tables 14-20), Detect Modules Override (Table 23) and the CoE
// Emergencies that announce them.
#include "modules/rack/events.hpp"
#include "rack_fixture.hpp"

using namespace rackcat;
using namespace rackcat::modules;
using namespace rackcat::modules::testing;

namespace {
constexpr uint16_t kRim2Info = 0x2021;
constexpr uint16_t kRim1Info = 0x2011;
}  // namespace

TEST_F(RackTest, AllOnlineAtStartNothingReported) {
  EXPECT_EQ(obj(kRim1Info).get_u(8), 2u);  // ONLINE
  EXPECT_EQ(obj(kRim2Info).get_u(8), 2u);
  EXPECT_EQ(obj(0xF380).get_u(0), 0u);
  EXPECT_EQ(obj(0xF388).get_u(1), 0u);
  EXPECT_TRUE(drain_emergencies().empty());
}

TEST_F(RackTest, UnplugAndReplugRimPropagatesAndLatchesUntilExceptionReset) {
  to_op();
  rack.set_rim_state(2, RimState::Offline);
  // 0x2rr1:08: active state OFFLINE (0) + latched "RIM state error" (bit 3).
  EXPECT_EQ(obj(kRim2Info).get_u(8), 0x8u);
  EXPECT_EQ(obj(0xF388).get_u(1), 1u << 2);  // bit rr for RIM rr
  EXPECT_EQ(obj(0xF398).get_u(1), 1u << 2);
  EXPECT_EQ(obj(0xF380).get_u(0), 0x8u);  // manufacturer error
  EXPECT_EQ(obj(0xF390).get_u(0), 0x8u);
  auto em = drain_emergencies();
  ASSERT_TRUE(has_code(em, 0xA001));
  EXPECT_EQ(em[0].data[0], 2);              // RIM 2
  EXPECT_EQ(em[0].data[2], 3);              // event bit 3
  EXPECT_EQ(device.state(), EsmState::Op);  // Detect Modules Override 1: state kept

  rack.set_rim_state(2, RimState::Online);
  EXPECT_EQ(obj(kRim2Info).get_u(8), 0xAu);  // ONLINE, bit 3 still latched
  EXPECT_EQ(obj(0xF388).get_u(1), 0u);
  EXPECT_EQ(obj(0xF398).get_u(1), 1u << 2);
  EXPECT_EQ(obj(0xF380).get_u(0), 0u);
  EXPECT_EQ(obj(0xF390).get_u(0), 0x8u);
  EXPECT_TRUE(has_code(drain_emergencies(), 0x0000));

  // 0xFBF1 through the dictionary's command hooks: latched bits whose cause is gone clear.
  coe::Object& reset = obj(0xFBF1);
  const uint8_t cmd[5] = {0x74, 0x65, 0x73, 0x65, 0x72};
  ASSERT_EQ(reset.hooks().validate_write(reset, 1, cmd, EsmState::Op), coe::AbortCode::None);
  std::copy(cmd, cmd + 5, reset.bytes(1).begin());
  reset.hooks().after_write(reset, 1);
  EXPECT_EQ(obj(kRim2Info).get_u(8), 0x2u);
  EXPECT_EQ(obj(0xF398).get_u(1), 0u);
  EXPECT_EQ(obj(0xF390).get_u(0), 0u);
}

TEST_F(RackTest, ExceptionResetKeepsLatchedBitsWhoseCauseIsActive) {
  rack.set_rim_state(2, RimState::Offline, /*comm_error=*/true);
  EXPECT_EQ(obj(kRim2Info).get_u(8), 0x18u);  // state error + communication error
  rack.on_exception_reset(device);
  EXPECT_EQ(obj(kRim2Info).get_u(8), 0x18u);
  EXPECT_EQ(obj(0xF398).get_u(1), 1u << 2);
  EXPECT_TRUE(has_code(drain_emergencies(), 0x7500));
}

TEST_F(RackTest, ConnectedNotOnlineIsAWarning) {
  rack.set_rim_state(2, RimState::Connected);
  EXPECT_EQ(obj(kRim2Info).get_u(8), 0x5u);  // CONNECTED + state warning (bit 2)
  EXPECT_EQ(obj(0xF386).get_u(1), 1u << 2);
  EXPECT_EQ(obj(0xF388).get_u(1), 0u);
  EXPECT_EQ(obj(0xF380).get_u(0), 0x2u);  // manufacturer warning
}

TEST_F(RackTest, MasksGateTheSummaryAndEventMasksTheGlobalDetails) {
  obj(0xF3A8).set_u(1, ~(1u << 2));  // RIM 2 errors not reported in the summary
  rack.set_rim_state(2, RimState::Offline);
  EXPECT_EQ(obj(0xF388).get_u(1), 1u << 2);
  EXPECT_EQ(obj(0xF380).get_u(0), 0u);
  rack.set_rim_state(2, RimState::Online);
  obj(0xF3A8).set_u(1, 0xFFFFFFFF);
  obj(kRim2Info).set_u(7, ~rim_event::kStateError);  // event mask: state error not reported
  rack.set_rim_state(2, RimState::Offline);
  EXPECT_EQ(obj(0xF388).get_u(1), 0u);
  EXPECT_EQ(obj(kRim2Info).get_u(8) & 0x8u, 0x8u);  // the event itself still shows
}

TEST_F(RackTest, OfflineRimDeEnergisesOutputsAndZeroesInputs) {
  CardDriver& dout = at(2, 7);
  CardDriver& din = at(2, 8);  // channels 0,1 looped from slot 7
  to_op();
  module_obj(dout, 0x7000, 0x0).set_u(1, 0x3);
  rack.set_source(din.module().number, 5, "constant", {{"value", "1"}});
  cycle();
  EXPECT_EQ(module_obj(din, 0x6000, 0x0).get_u(1), 0x23u);
  rack.set_rim_state(2, RimState::Offline);
  cycle();
  EXPECT_EQ(dout.outputs()[0].driven, 0.0);
  EXPECT_EQ(module_obj(din, 0x6000, 0x0).get_u(1), 0u);
  rack.set_rim_state(2, RimState::Online);
  cycle();
  EXPECT_EQ(dout.outputs()[0].driven, 1.0);
  EXPECT_EQ(module_obj(din, 0x6000, 0x0).get_u(1), 0x23u);
}

TEST_F(RackTest, DetectModulesOverrideZeroTakesTheDeviceToSafeOp) {
  std::vector<std::pair<EsmState, uint16_t>> requests;
  rack.set_state_request_handler(
      [&](EsmState to, uint16_t code) { requests.emplace_back(to, code); });
  obj(0x2000).set_u(0x0B, 0);
  to_op();
  rack.set_rim_state(2, RimState::Offline);
  ASSERT_EQ(requests.size(), 1u);
  EXPECT_EQ(requests[0].first, EsmState::SafeOp);
  EXPECT_EQ(requests[0].second, kAlStatusModuleMissing);
  go(EsmState::Op, EsmState::SafeOp);
  // Back to OP is refused while the RIM is gone, accepted once it is back.
  EXPECT_EQ(rack.check_state_request(EsmState::SafeOp, EsmState::Op), kAlStatusModuleMissing);
  rack.set_rim_state(2, RimState::Online);
  EXPECT_EQ(rack.check_state_request(EsmState::SafeOp, EsmState::Op), 0);
}

TEST_F(RackTest, DetectModulesOverrideOneKeepsTheState) {
  bool requested = false;
  rack.set_state_request_handler([&](EsmState, uint16_t) { requested = true; });
  to_op();
  rack.set_rim_state(2, RimState::Offline);
  EXPECT_FALSE(requested);
  EXPECT_EQ(rack.check_state_request(EsmState::SafeOp, EsmState::Op), 0);
}

TEST_F(RackTest, DetectModulesOverrideZeroIgnoresRimsWithoutMappedProcessData) {
  bool requested = false;
  rack.set_state_request_handler([&](EsmState, uint16_t) { requested = true; });
  obj(0x2000).set_u(0x0B, 0);
  // Assign only the first module's PDOs (RIM 1).
  obj(0x1C12).image()[0] = 1;
  obj(0x1C12).set_u(1, 0x1600);
  obj(0x1C13).image()[0] = 1;
  obj(0x1C13).set_u(1, 0x1A01);
  to_op();
  rack.set_rim_state(2, RimState::Offline);
  EXPECT_FALSE(requested);
}

TEST_F(RackTest, SafeWiringFaultSetsManufacturerWarningDetails) {
  CardDriver& dout = at(1, 1);  // CDO-10 sourcing outputs
  const uint16_t n = dout.module().number;
  to_op();
  module_obj(dout, 0x7000, 0x0).set_u(1, 0x0008);
  cycle();
  rack.set_wiring_fault(n, 3, WiringFault::ShortToGround);  // driven high, reads low
  cycle();
  EXPECT_EQ(obj(0xF382).get_u(static_cast<uint8_t>(n)), 0x8u);
  EXPECT_EQ(obj(0xF392).get_u(static_cast<uint8_t>(n)), 0x8u);
  EXPECT_EQ(obj(0xF380).get_u(0), 0x2u);
  EXPECT_EQ(obj(kRim1Info).get_u(8), 2u);  // a safe fault keeps the RIM online
  auto em = drain_emergencies();
  ASSERT_TRUE(has_code(em, 0x2330));
  // The loopback input sees the wire, not the command.
  EXPECT_EQ(module_obj(at(1, 2), 0x6000, 0x0).get_u(1), 0u);
  rack.set_wiring_fault(n, 3, WiringFault::None);
  cycle();
  EXPECT_EQ(obj(0xF382).get_u(static_cast<uint8_t>(n)), 0u);
  EXPECT_EQ(obj(0xF392).get_u(static_cast<uint8_t>(n)), 0x8u);
  EXPECT_EQ(obj(0xF390).get_u(0), 0x2u);
}

TEST_F(RackTest, UnsafeWiringFaultTakesTheRimOutOfOnline) {
  CardDriver& dout = at(2, 7);
  const uint16_t n = dout.module().number;
  to_op();
  cycle();
  rack.set_wiring_fault(n, 5, WiringFault::ShortToSupply);  // driven low, reads high
  cycle();
  EXPECT_EQ(obj(0xF384).get_u(static_cast<uint8_t>(n)), 1u << 5);
  EXPECT_EQ(obj(0xF380).get_u(0) & 0x8u, 0x8u);
  EXPECT_EQ(obj(kRim2Info).get_u(8) & 0x3u, 3u);  // ERROR
  EXPECT_EQ(obj(0xF388).get_u(1), 1u << 2);
  EXPECT_TRUE(has_code(drain_emergencies(), 0x2320));
  rack.set_wiring_fault(n, 5, WiringFault::None);
  cycle();
  EXPECT_EQ(obj(kRim2Info).get_u(8) & 0x3u, 2u);
  EXPECT_THROW(rack.set_wiring_fault(at(1, 5).module().number, 0, WiringFault::ShortToGround),
               std::invalid_argument);  // sinking outputs cannot detect wiring faults
}

TEST_F(RackTest, FanDeviationThresholds) {
  rack.set_fan_rpm(1, "slot_card", 2000.0);  // -33 %: warning + error
  EXPECT_NEAR(real(kRim1Info, 0x0B), -33.33f, 0.01);
  EXPECT_FLOAT_EQ(real(kRim1Info, 0x0D), 2000.0f);
  EXPECT_EQ(obj(kRim1Info).get_u(8), 0x302u);
  EXPECT_EQ(obj(0xF386).get_u(1), 1u << 1);
  EXPECT_EQ(obj(0xF388).get_u(1), 1u << 1);
  EXPECT_TRUE(has_code(drain_emergencies(), 0x5000));
  rack.set_fan_rpm(0, "cpu", 2400.0);  // CPU fan -20 %: device warning
  EXPECT_EQ(obj(0x2000).get_u(0x0A), 0x100u);
  EXPECT_EQ(obj(0xF386).get_u(1), (1u << 1) | 1u);
  // RIM 2 has no power-supply fan: -100 % and 0 RPM, and it cannot be set.
  EXPECT_FLOAT_EQ(real(kRim2Info, 0x0A), -100.0f);
  EXPECT_FLOAT_EQ(real(kRim2Info, 0x0C), 0.0f);
  EXPECT_THROW(rack.set_fan_rpm(2, "power_supply", 100.0), std::invalid_argument);
}

TEST_F(RackTest, CpuTemperatureHalfDegreeEveryThirtySeconds) {
  EXPECT_FLOAT_EQ(real(0x2000, 0x0F), 42.0f);
  rack.set_cpu_temperature(90.3, false);
  cycle();
  EXPECT_FLOAT_EQ(real(0x2000, 0x0F), 42.0f);  // not yet: 30 s update period
  drain_emergencies();
  for (int k = 0; k < 30000; ++k) cycle();
  EXPECT_FLOAT_EQ(real(0x2000, 0x0F), 90.5f);
  EXPECT_TRUE(has_code(drain_emergencies(), 0x4210));
}

TEST_F(RackTest, SafetyControllerErrorsAreRimErrors) {
  rack.set_rim_mcm_errors(1, rim_event::kSoutCompareMcm1);
  EXPECT_EQ(obj(kRim1Info).get_u(8), (1u << 19) | 2u);
  EXPECT_EQ(obj(0xF388).get_u(1), 1u << 1);
  EXPECT_TRUE(has_code(drain_emergencies(), 0x6000));
  rack.set_fan_rpm(1, "slot_card", 3000.0);  // fan updates keep the MCM cause
  EXPECT_EQ(obj(0xF388).get_u(1), 1u << 1);
  rack.set_rim_mcm_errors(1, 0);
  EXPECT_EQ(obj(0xF388).get_u(1), 0u);
  EXPECT_EQ(obj(kRim1Info).get_u(8), (1u << 19) | 2u);  // latched until 0xFBF1
  EXPECT_THROW(rack.set_rim_mcm_errors(1, 1u << 3), std::invalid_argument);
}
