// Rack behaviour an audit against the guide found wrong: exception masks re-evaluate the tree
// when written (§3.4), a RIM put into ERROR stays there (Table 16 state 3), and 0x2000:0F follows
// the device's own 30 s clock in every state (§4.8), not only while process data flows.
#include <gtest/gtest.h>

#include "rack_fixture.hpp"
#include "tests/support/coe_frames.hpp"

namespace rackcat::modules {
namespace {

using rackcat::EsmState;
using testing::RackTest;

constexpr uint16_t kRim2Info = 0x2021;

// An expedited 4-byte SDO download (tests/support/coe_frames.hpp) through the device's CoE;
// returns the SDO command byte of the reply (0x60 = done, 0x80 = abort).
uint8_t sdo_write_u32(mdp::Device& device, uint16_t index, uint8_t sub, uint32_t value) {
  static uint8_t counter = 0;
  counter = static_cast<uint8_t>(counter % 7 + 1);
  const rackcat::testing::Bytes req = rackcat::testing::coe_message(
      counter, 2, rackcat::testing::download_expedited(index, sub, value, 4));
  uint8_t reply[128] = {};
  // The mailbox data after the 6-byte header: what the firmware hands the device's CoE.
  const auto answer = device.coe_request(std::span(req).subspan(6), reply);
  return answer.length >= 3 ? reply[2] : 0xFF;
}

TEST_F(RackTest, ExceptionMaskWriteReevaluatesTheTreeAtOnce) {
  go(EsmState::Init, EsmState::PreOp);
  rack.set_rim_state(2, RimState::Offline);
  ASSERT_EQ(obj(0xF380).get_u(0) & 0x8u, 0x8u);  // manufacturer error
  // No process data, no new cause: the mask write alone updates 0xF380.
  ASSERT_EQ(sdo_write_u32(device, 0xF3A8, 1, ~(1u << 2)), 0x60);
  EXPECT_EQ(obj(0xF380).get_u(0) & 0x8u, 0u);
  ASSERT_EQ(sdo_write_u32(device, 0xF3A8, 1, 0xFFFFFFFF), 0x60);
  EXPECT_EQ(obj(0xF380).get_u(0) & 0x8u, 0x8u);
  // The RIM event mask likewise gates 0xF388.
  ASSERT_EQ(sdo_write_u32(device, kRim2Info, 7, ~rim_event::kStateError & ~rim_event::kCommError),
            0x60);
  EXPECT_EQ(obj(0xF388).get_u(1) & (1u << 2), 0u);
}

TEST_F(RackTest, RimStateErrorHoldsUntilChangedAgain) {
  to_op();
  cycle();
  rack.set_rim_state(2, RimState::Error);
  for (int k = 0; k < 10; ++k) cycle();
  EXPECT_EQ(obj(kRim2Info).get_u(8) & 0x3u, 3u);  // ERROR (guide Table 16 state 3)
  rack.set_rim_state(2, RimState::Online);
  cycle();
  EXPECT_EQ(obj(kRim2Info).get_u(8) & 0x3u, 2u);
}

TEST_F(RackTest, CpuTemperatureFollowsTheDeviceClockWithoutProcessData) {
  go(EsmState::Init, EsmState::PreOp);
  rack.set_cpu_temperature(61.2, false);
  clock += 29.0;
  rack.on_clock();
  EXPECT_FLOAT_EQ(real(0x2000, 0x0F), 42.0f);  // the previous reading, 30 s period
  clock += 2.0;
  rack.on_clock();
  EXPECT_FLOAT_EQ(real(0x2000, 0x0F), 61.0f);  // 0.5 °C resolution
}

}  // namespace
}  // namespace rackcat::modules
