// A master that repeats its output data gets the same inputs without a round through the
// cards (mdp/repeated_cycles.hpp, issue 16), also when it reads them in a frame of their own,
// and still sees at once everything that changes them in between: new output data, a control
// command, a dictionary write, an SDO request, a time-varying source, the rack's own 30 s CPU
// temperature reading, the input latch time 0xF6F0. Driven the way the firmware drives the device:
// one SM2 and one SM3 buffer kept across cycles, SM3 written only when read_inputs() packed it
// (ecat/slave/process_data.cpp).
#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "base/mailbox_error.hpp"
#include "rack_fixture.hpp"

using namespace rackcat;
using namespace rackcat::modules;

namespace {

// examples/tiny-rack.yaml: an 8-channel relay card (RIM 1 slot 1) wired back to an 8-channel
// input card (slot 2).
class RepeatedCycleTest : public ::testing::Test {
 protected:
  RepeatedCycleTest()
      : device(mdp::load_rack_config(std::string(RACKCAT_SOURCE_DIR) + "/examples/tiny-rack.yaml"),
               modules::testing::device_options()),
        rack(device, modules::testing::rack_options(&clock)) {
    device.state_changed(EsmState::Init, EsmState::PreOp);
    device.state_changed(EsmState::PreOp, EsmState::SafeOp);
    device.state_changed(EsmState::SafeOp, EsmState::Op);
    sm2.assign(device.output_bytes(), 0);
    sm3.assign(device.input_bytes(), 0);
  }

  // One cycle of 1 ms with `word` as the relay card's output data: true when the device
  // packed the inputs (a full cycle), false when it skipped a repeated one.
  bool cycle(uint8_t word) {
    clock += 0.001;
    sm2[0] = word;
    device.write_outputs(sm2);
    return device.read_inputs(sm3);
  }
  // Cycles with `word` until the device skips one (at most 5): the number of full ones, -1
  // when none was skipped.
  int settle(uint8_t word) {
    for (int full = 0; full < 5; ++full) {
      if (!cycle(word)) return full;
    }
    return -1;
  }
  CardDriver& relay() { return *rack.driver_at(1, 1); }
  CardDriver& inputs() { return *rack.driver_at(1, 2); }

  double clock = 0.0;
  mdp::Device device;
  Rack rack;
  std::vector<uint8_t> sm2, sm3;
};

}  // namespace

TEST_F(RepeatedCycleTest, RepeatedOutputsAreAnsweredFromTheLastInputsOnceTwoFullCyclesAgree) {
  ASSERT_EQ(sm2.size(), 1u);
  ASSERT_EQ(sm3.size(), 1u);
  EXPECT_TRUE(cycle(0x5A));
  EXPECT_EQ(sm3[0], 0x5A);  // the loopback within the cycle
  // The next full cycle finds the recorded outputs and inputs again and settles (one more
  // when the first cycle in OP also updated the exception tree).
  const int full = settle(0x5A);
  EXPECT_GE(full, 1);
  EXPECT_LE(full, 2);
  EXPECT_EQ(sm3[0], 0x5A);
  for (int i = 0; i < 10; ++i) {
    EXPECT_FALSE(cycle(0x5A)) << "cycle " << i;
    EXPECT_EQ(sm3[0], 0x5A);
  }
  // New output data: a full cycle at once, its loopback in the same cycle.
  EXPECT_TRUE(cycle(0xA5));
  EXPECT_EQ(sm3[0], 0xA5);
  EXPECT_EQ(settle(0xA5), 1);
  EXPECT_EQ(sm3[0], 0xA5);
}

TEST_F(RepeatedCycleTest, AControlCommandBetweenRepeatsIsSeenOnTheNextCycle) {
  ASSERT_GE(settle(0xFE), 2);
  EXPECT_EQ(sm3[0], 0xFE);
  // `rackcat ctl source`: input 0 reads a constant 1 instead of the relay's open contact.
  rack.set_source(inputs().module().number, 0, "constant", {{"value", "1"}});
  EXPECT_TRUE(cycle(0xFE));
  EXPECT_EQ(sm3[0], 0xFF);
  ASSERT_GE(settle(0xFE), 1);
  // ...and input 1 a constant 0 although its relay contact is closed.
  rack.set_source(inputs().module().number, 1, "constant", {{"value", "0"}});
  EXPECT_TRUE(cycle(0xFE));
  EXPECT_EQ(sm3[0], 0xFD);
  ASSERT_GE(settle(0xFE), 1);
  EXPECT_EQ(sm3[0], 0xFD);
}

TEST_F(RepeatedCycleTest, ARimLostBetweenRepeatsReadsItsSubstitutesOnTheNextCycle) {
  ASSERT_GE(settle(0x0F), 2);
  rack.set_rim_state(1, RimState::Offline);
  EXPECT_TRUE(cycle(0x0F));
  EXPECT_EQ(sm3[0], 0x00);
  rack.set_rim_state(1, RimState::Online);
  EXPECT_TRUE(cycle(0x0F));
  EXPECT_EQ(sm3[0], 0x0F);
}

TEST_F(RepeatedCycleTest, AWriteThroughTheDictionaryBetweenRepeatsIsUndoneByTheNextCycle) {
  ASSERT_GE(settle(0x33), 2);
  // Whoever takes the mutable dictionary (the SDO server, the control API) may change what
  // the cycle packs: here the input object itself, which the next cycle samples again.
  coe::Object* din = device.dictionary().find(inputs().module().index(0x6000, 0x1));
  ASSERT_NE(din, nullptr);
  din->set_u(1, 0x00);
  EXPECT_TRUE(cycle(0x33));
  EXPECT_EQ(sm3[0], 0x33);
}

TEST_F(RepeatedCycleTest, AnSdoRequestBetweenRepeatsRunsTheNextCycleInFull) {
  ASSERT_GE(settle(0x42), 2);
  // CoE header (ETG.1000.6 §5.6.1: service 2, SDO request), initiate upload (0x40) of 0x1018:01.
  const std::vector<uint8_t> upload = {0x00, 0x20, 0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0};
  std::vector<uint8_t> reply(64);
  const mailbox::Answer a = device.coe_request(upload, reply);
  ASSERT_EQ(a.error, mailbox::Error::None);
  ASSERT_EQ(a.length, 10u);
  EXPECT_EQ(reply[2], 0x43);  // expedited upload response, 4 bytes
  // The SDO server may have changed anything the cycle reads: the next one runs in full, and
  // it takes two agreeing full cycles to settle again.
  EXPECT_TRUE(cycle(0x42));
  EXPECT_EQ(sm3[0], 0x42);
  EXPECT_EQ(settle(0x42), 1);
}

TEST_F(RepeatedCycleTest, AMasterReadingTheInputsInAFrameOfTheirOwnSettlesToo) {
  // LWR, then LRD: the firmware hands the outputs over and packs the inputs on the LWR's SM2
  // event, and packs them again on the LRD's SM3 event with no new outputs in between.
  const auto refresh = [this] { return device.read_inputs(sm3); };
  EXPECT_TRUE(cycle(0x3C));
  EXPECT_EQ(sm3[0], 0x3C);
  EXPECT_TRUE(refresh());  // not settled yet: packed again, and the recording stands
  EXPECT_EQ(sm3[0], 0x3C);
  // The next full cycle finds the recorded outputs and inputs and settles (one more when the
  // first cycle in OP also updated the exception tree): from then on the LRD's refresh is
  // skipped as well.
  int full = 0;
  for (; full < 5; ++full) {
    ASSERT_TRUE(cycle(0x3C));
    if (!refresh()) break;
  }
  EXPECT_LE(full, 1);
  for (int i = 0; i < 10; ++i) {
    EXPECT_FALSE(refresh()) << "refresh " << i;
    EXPECT_FALSE(cycle(0x3C)) << "cycle " << i;
    EXPECT_EQ(sm3[0], 0x3C);
  }
  // A control command between the LWR and the LRD: the LRD's refresh packs its effect.
  rack.set_source(inputs().module().number, 0, "constant", {{"value", "1"}});
  EXPECT_TRUE(refresh());
  EXPECT_EQ(sm3[0], 0x3D);
  // That refresh packed other inputs than the recorded ones: the next full cycle records anew
  // and one more settles.
  EXPECT_TRUE(cycle(0x3C));
  EXPECT_TRUE(refresh());
  EXPECT_TRUE(cycle(0x3C));
  EXPECT_FALSE(refresh());
  EXPECT_FALSE(cycle(0x3C));
  EXPECT_EQ(sm3[0], 0x3D);
}

TEST_F(RepeatedCycleTest, InputsThatMoveWithTimeAreRefreshedEveryTime) {
  rack.set_source(inputs().module().number, 3, "sine",
                  {{"amplitude", "1"}, {"frequency", "50"}, {"offset", "0.5"}});
  for (int i = 0; i < 10; ++i) {
    EXPECT_TRUE(cycle(0x01)) << "cycle " << i;
    clock += 0.001;
    EXPECT_TRUE(device.read_inputs(sm3)) << "refresh " << i;
  }
}

TEST_F(RepeatedCycleTest, LeavingOpAndComingBackRunsInFull) {
  ASSERT_GE(settle(0x81), 2);
  device.state_changed(EsmState::Op, EsmState::SafeOp);
  device.state_changed(EsmState::SafeOp, EsmState::Op);
  // The relay drives its substitute (0) until the first valid output data in OP.
  EXPECT_TRUE(cycle(0x81));
  EXPECT_EQ(sm3[0], 0x81);
}

TEST_F(RepeatedCycleTest, ATimeVaryingSourceNeverRepeats) {
  rack.set_source(inputs().module().number, 3, "sine",
                  {{"amplitude", "1"}, {"frequency", "50"}, {"offset", "0.5"}});
  for (int i = 0; i < 20; ++i) EXPECT_TRUE(cycle(0x01)) << "cycle " << i;
}

TEST_F(RepeatedCycleTest, TheRacksThirtySecondCpuTemperatureStillPublishes) {
  rack.set_cpu_temperature(55.0, false);  // read by the next 30 s publication
  ASSERT_GE(settle(0x01), 1);
  ASSERT_NE(rack.cpu_temperature_published(), 55.0);
  clock += 31.0;
  EXPECT_TRUE(cycle(0x01));
  EXPECT_EQ(rack.cpu_temperature_published(), 55.0);
}

TEST_F(RepeatedCycleTest, TheInputLatchTimeFollowsRepeatedCycles) {
  const coe::Object* latch = std::as_const(device).dictionary().find(0xF6F0);
  ASSERT_NE(latch, nullptr);
  ASSERT_GE(settle(0x01), 2);
  const uint64_t before = std::as_const(device).dictionary().find(0xF6F0)->get_u(1);
  std::this_thread::sleep_for(std::chrono::milliseconds(3));
  EXPECT_FALSE(cycle(0x01));
  // The latch time of the skipped cycle, at least 3 ms after the last full one.
  EXPECT_GE(std::as_const(device).dictionary().find(0xF6F0)->get_u(1), before + 3000);
}
