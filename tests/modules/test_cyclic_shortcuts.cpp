// The cyclic path's shortcuts (issue 16) change nothing a master or the control API sees: a
// digital output card skips its channel work while the master repeats its output data, a
// digital input card its code stores and its substitute pass while its inputs stay the same;
// anything that drives an output or changes a code in between (safe state, wiring fault, RIM
// loss, substitute values, a new source) is still seen on the next cycle.
#include <stdexcept>

#include "mdp/substitute_values.hpp"
#include "rack_fixture.hpp"

using namespace rackcat;
using namespace rackcat::modules;
using namespace rackcat::modules::testing;

namespace {

class CyclicShortcutTest : public RackTest {
 protected:
  struct LoopedPair {
    CardDriver& dout;  // RIM 2 slot 7
    CardDriver& din;   // RIM 2 slot 8, channels 0,1 looped from slot 7
  };
  // The looped cards in OP after one cycle with `word` as the output card's data.
  LoopedPair looped_pair_in_op(uint64_t word) {
    LoopedPair p{at(2, 7), at(2, 8)};
    to_op();
    module_obj(p.dout, 0x7000, 0x0).set_u(1, word);
    cycle();
    return p;
  }
};

}  // namespace

TEST_F(CyclicShortcutTest, RepeatedOutputsAfterASafeStateAreDrivenAgain) {
  auto [dout, din] = looped_pair_in_op(0x3);
  cycle();  // same output data: the shortcut
  EXPECT_EQ(dout.outputs()[1].driven, 1.0);
  EXPECT_EQ(module_obj(din, 0x6000, 0x0).get_u(1) & 0x3u, 0x3u);
  // Leaving OP drives the substitute values (0x4nn0 default: all off)...
  go(EsmState::Op, EsmState::SafeOp);
  cycle();
  EXPECT_EQ(dout.outputs()[1].driven, 0.0);
  EXPECT_EQ(module_obj(din, 0x6000, 0x0).get_u(1) & 0x3u, 0u);
  // ...and back in OP the unchanged output data is driven again.
  go(EsmState::SafeOp, EsmState::Op);
  cycle();
  EXPECT_EQ(dout.outputs()[0].driven, 1.0);
  EXPECT_EQ(dout.outputs()[1].driven, 1.0);
  EXPECT_EQ(module_obj(din, 0x6000, 0x0).get_u(1) & 0x3u, 0x3u);
}

TEST_F(CyclicShortcutTest, WiringFaultBetweenRepeatedOutputsReachesTheLoopback) {
  auto [dout, din] = looped_pair_in_op(0x3);
  EXPECT_EQ(module_obj(din, 0x6000, 0x0).get_u(1) & 0x3u, 0x3u);
  // A short to ground (a safe wiring fault, guide §4.7): the wire reads 0 although driven.
  rack.set_wiring_fault(dout.module().number, 0, WiringFault::ShortToGround);
  cycle();
  EXPECT_EQ(module_obj(din, 0x6000, 0x0).get_u(1) & 0x3u, 0x2u);
  EXPECT_EQ(dout.outputs()[0].driven, 1.0);
  rack.set_wiring_fault(dout.module().number, 0, WiringFault::None);
  cycle();
  EXPECT_EQ(module_obj(din, 0x6000, 0x0).get_u(1) & 0x3u, 0x3u);
  EXPECT_EQ(dout.outputs()[0].wire, 1.0);
}

TEST_F(CyclicShortcutTest, SubstituteCodesGiveWayToTheSameInputsAfterTheRimReturns) {
  auto [dout, din] = looped_pair_in_op(0x3);
  const auto before = module_obj(din, 0x6000, 0x0).get_u(1);
  ASSERT_EQ(before & 0x3u, 0x3u);
  ASSERT_EQ(din.inputs()[0].code, 1u);
  // RIM lost: the input codes are 0 (or their substitutes), then the very same inputs return.
  rack.set_rim_state(2, RimState::Offline);
  cycle();
  EXPECT_EQ(din.inputs()[0].code, 0u);
  rack.set_rim_state(2, RimState::Online);
  cycle();
  cycle();
  EXPECT_EQ(din.inputs()[0].code, 1u);
  EXPECT_EQ(din.inputs()[1].code, 1u);
  EXPECT_EQ(module_obj(din, 0x6000, 0x0).get_u(1), before);
}

TEST_F(CyclicShortcutTest, AnOfflineRimIsLeftOutOfTheCycleUntilItReturns) {
  auto [dout, din] = looped_pair_in_op(0x1);
  ASSERT_EQ(dout.outputs()[0].driven, 1.0);
  rack.set_rim_state(2, RimState::Offline);
  // New output data while the RIM is offline is not driven, and its inputs read 0.
  module_obj(dout, 0x7000, 0x0).set_u(1, 0x3);
  cycle();
  cycle();
  EXPECT_EQ(dout.outputs()[0].driven, 0.0);
  EXPECT_EQ(dout.outputs()[1].driven, 0.0);
  EXPECT_EQ(module_obj(din, 0x6000, 0x0).get_u(1), 0u);
  // Back online: the outputs follow the master's data at once, the inputs with the next cycle.
  rack.set_rim_state(2, RimState::Online);
  EXPECT_EQ(dout.outputs()[1].driven, 1.0);
  module_obj(dout, 0x7000, 0x0).set_u(1, 0x2);
  cycle();
  EXPECT_EQ(dout.outputs()[0].driven, 0.0);
  EXPECT_EQ(dout.outputs()[1].driven, 1.0);
  EXPECT_EQ(module_obj(din, 0x6000, 0x0).get_u(1) & 0x3u, 0x2u);
}

// A card samples a loopback or constant source from its own copy of the source's gain, offset
// and output (Source::affine): replacing the source changes that copy, on the next cycle.
TEST_F(CyclicShortcutTest, AReplacedSourceIsSampledOnTheNextCycle) {
  auto [dout, din] = looped_pair_in_op(0x3);
  const uint16_t module = din.module().number;
  const auto din_bits = [this, &card = din] {
    return module_obj(card, 0x6000, 0x0).get_u(1) & 0x3u;
  };
  ASSERT_EQ(din_bits(), 0x3u);
  rack.set_source(module, 0, "constant", {{"value", "0"}});
  cycle();
  EXPECT_EQ(din_bits(), 0x2u);
  EXPECT_EQ(din.inputs()[0].value, 0.0);
  // Channel 0 reads slot 7's channel 1 inverted: 1 - output.
  rack.set_source(module, 0, "loopback",
                  {{"rim", "2"}, {"slot", "7"}, {"channel", "1"}, {"gain", "-1"}, {"offset", "1"}});
  cycle();
  EXPECT_EQ(din_bits(), 0x2u);
  module_obj(dout, 0x7000, 0x0).set_u(1, 0x1);
  cycle();  // slot 7 drives 0x1 now
  cycle();  // and the inputs see it
  EXPECT_EQ(din_bits(), 0x1u);
  EXPECT_EQ(din.inputs()[0].value, 1.0);
  rack.set_source(module, 0, "sine", {{"amplitude", "0"}, {"frequency", "1"}, {"offset", "0.75"}});
  cycle();
  EXPECT_EQ(din.inputs()[0].value, 0.75);
  EXPECT_NE(din.source(0).describe().find("sine"), std::string::npos);
  // No source is no change.
  EXPECT_THROW(din.set_source(0, nullptr), std::invalid_argument);
  cycle();
  EXPECT_EQ(din.inputs()[0].value, 0.75);
}

// While the inputs repeat, substitute_inputs() leaves the channels alone; the last valid codes
// still follow every change, so a RIM lost after a stretch of repeated inputs holds the latest.
TEST_F(CyclicShortcutTest, HoldLastAfterRepeatedInputsHoldsTheLatestCodes) {
  auto [dout, din] = looped_pair_in_op(0x3);
  namespace sv = mdp::substitute;
  coe::Object& reaction = module_obj(din, 0x4000, sv::kInputReaction);
  for (uint8_t s = 1; s <= 2; ++s) reaction.set_u(s, sv::kHoldLast);
  for (int k = 0; k < 3; ++k) cycle();
  module_obj(dout, 0x7000, 0x0).set_u(1, 0x1);
  for (int k = 0; k < 4; ++k) cycle();  // the new inputs, then repeated
  ASSERT_EQ(module_obj(din, 0x6000, 0x0).get_u(1) & 0x3u, 0x1u);
  rack.set_rim_state(2, RimState::Offline);
  cycle();
  EXPECT_EQ(din.inputs()[0].code, 1u);
  EXPECT_EQ(din.inputs()[1].code, 0u);
  EXPECT_EQ(module_obj(din, 0x4000, sv::kInputStatus).get_u(0) & 0x3u, 0x3u);
  rack.set_rim_state(2, RimState::Online);
  cycle();
  cycle();
  EXPECT_EQ(module_obj(din, 0x4000, sv::kInputStatus).get_u(0), 0u);
  EXPECT_EQ(module_obj(din, 0x6000, 0x0).get_u(1) & 0x3u, 0x1u);
}
