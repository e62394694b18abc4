// Substitute values (mdp/substitute_values.hpp, INTERBUS Basic profile §7.3.2 and its objects
// 0x0020 PDTimeoutCode / 0x0030 PF_Code / 0x0031 PDIN_Subst): every output reaction on leaving
// OP and on the SM watchdog, every input reaction while a RIM is offline or a sensor is open,
// the status bits 0x4nnC, and the guide's behaviour (0x8000) unchanged by default.
#include "modules/cards/analog_scale.hpp"
#include "modules/cards/substitute.hpp"
#include "modules/cards/temperature_scale.hpp"
#include "rack_fixture.hpp"

using namespace rackcat;
using namespace rackcat::modules;
using namespace rackcat::modules::testing;
namespace sv = rackcat::mdp::substitute;

namespace {
// Default rack (examples/default-rack.yaml): RIM 1 slot 1 CDO-10, slot 11 CAO-15, slot 15
// CTP-11 (K); RIM 2 slot 1 CDI-13 (8x DI), slot 4 CAI-11/X8.
constexpr uint8_t kRim1 = 1, kRim2 = 2;

uint32_t driven_word(const CardDriver& d) {
  uint32_t w = 0;
  for (size_t i = 0; i < d.outputs().size(); ++i)
    w |= (d.outputs()[i].driven >= 0.5 ? 1u : 0u) << i;
  return w;
}
}  // namespace

// The profile's table, one channel per code (PDTimeoutCode 0x0020).
TEST(SubstituteRules, OutputCodesFollowThePdTimeoutCodeTable) {
  const ChannelCodes analog{0xFFFF, 0x8001, 0x7FFF};
  EXPECT_EQ(output_substitute(sv::kZeros, 7, 0x1234, 0x0555, analog), 0u);
  EXPECT_EQ(output_substitute(sv::kOnes, 7, 0x1234, 0x0555, analog), 0xFFFFu);
  EXPECT_EQ(output_substitute(sv::kHoldLast, 7, 0x1234, 0x0555, analog), 0x1234u);
  EXPECT_EQ(output_substitute(sv::kSubstitute, 7, 0x1234, 0x0555, analog), 0x0555u);
  EXPECT_EQ(output_substitute(sv::kMinimum, 7, 0x1234, 0x0555, analog), 0x8001u);
  EXPECT_EQ(output_substitute(sv::kMaximum, 7, 0x1234, 0x0555, analog), 0x7FFFu);
  EXPECT_EQ(output_substitute(sv::kGuide, 7, 0x1234, 0x0555, analog), 7u);
  EXPECT_TRUE(sv::valid_output_reaction(0x0005));
  EXPECT_FALSE(sv::valid_output_reaction(0x0006));
  EXPECT_FALSE(sv::valid_output_reaction(0x0010));  // subbus behaviour: not a subbus master
  EXPECT_EQ(input_substitute(sv::kZeros, 0x7FFF, 12, 34), 0u);
  EXPECT_EQ(input_substitute(sv::kHoldLast, 0x7FFF, 12, 34), 12u);
  EXPECT_EQ(input_substitute(sv::kSubstitute, 0x7FFF, 12, 34), 34u);
  EXPECT_EQ(input_substitute(sv::kGuide, 0x7FFF, 12, 34), 0x7FFFu);
  EXPECT_FALSE(sv::valid_input_reaction(sv::kOnes));
}

TEST_F(RackTest, SubstituteObjectsDefaultToTheGuidesRule) {
  CardDriver& dout = at(kRim1, 1);
  CardDriver& din = at(kRim2, 1);
  coe::Object& out_reaction = module_obj(dout, 0x4000, sv::kOutputReaction);
  EXPECT_EQ(out_reaction.sub0(), 16);
  for (uint8_t s = 1; s <= 16; ++s) EXPECT_EQ(out_reaction.get_u(s), sv::kGuide);
  EXPECT_EQ(module_obj(din, 0x4000, sv::kInputReaction).sub0(), 8);
  EXPECT_EQ(module_obj(din, 0x4000, sv::kInputValue).sub0(), 8);
  EXPECT_EQ(module_obj(din, 0x4000, sv::kInputStatus).get_u(0), 0u);
  // Input-only and output-only modules have only their side.
  EXPECT_EQ(device.dictionary().find(dout.module().index(0x4000, sv::kInputReaction)), nullptr);
  EXPECT_EQ(device.dictionary().find(din.module().index(0x4000, sv::kOutputReaction)), nullptr);
}

TEST_F(RackTest, DigitalOutputReactionsOnLeavingOp) {
  CardDriver& dout = at(kRim1, 1);
  coe::Object& reaction = module_obj(dout, 0x4000, sv::kOutputReaction);
  const uint16_t codes[] = {sv::kZeros,   sv::kOnes,    sv::kHoldLast, sv::kSubstitute,
                            sv::kMinimum, sv::kMaximum, sv::kGuide};
  for (uint8_t c = 0; c < 7; ++c) reaction.set_u(c + 1, codes[c]);
  coe::Object& safe = module_obj(dout, 0x4000, 0x0);  // guide Table 7
  safe.set_u(3, 0x0008);                              // Value: channel 3 = 1
  for (EsmState target : {EsmState::SafeOp, EsmState::Init}) {
    to_op();
    module_obj(dout, 0x7000, 0x0).set_u(1, 0x0055);  // channels 0, 2, 4, 6 on
    cycle();
    go(EsmState::Op, target);
    // 0 zeros -> 0, 1 ones -> 1, 2 hold -> 1, 3 Value -> 1, 4 min -> 0, 5 max -> 1,
    // 6 guide (not enabled in 0x4nn0:01) -> de-energised 0; 7..15 guide -> 0.
    EXPECT_EQ(driven_word(dout), 0x002Eu) << "to state " << int(target);
    if (target != EsmState::Init) go(target, EsmState::Init);
  }
}

TEST_F(RackTest, AnalogOutputReactionsOnTheWatchdog) {
  CardDriver& aout = at(kRim1, 11);  // CAO-15, -10..10 V
  coe::Object& reaction = module_obj(aout, 0x4000, sv::kOutputReaction);
  const uint16_t codes[] = {sv::kZeros,   sv::kOnes,    sv::kHoldLast, sv::kSubstitute,
                            sv::kMinimum, sv::kMaximum, sv::kGuide};
  for (uint8_t c = 0; c < 7; ++c) reaction.set_u(c + 1, codes[c]);
  const AnalogScale s{-10, 10};
  coe::Object& safe = module_obj(aout, 0x4000, 0x2);  // guide Table 9
  safe.set_u(3 + 3, s.to_code(-2.5));                 // Value[3]
  to_op();
  for (uint8_t c = 1; c <= 8; ++c) module_obj(aout, 0x7000, 0x2).set_u(c, s.to_code(6.0));
  cycle();
  device.watchdog_expired();
  EXPECT_EQ(aout.outputs()[0].code, 0u);
  EXPECT_EQ(aout.outputs()[1].code, 0xFFFFu);  // all bits: -1 LSB
  EXPECT_EQ(aout.outputs()[2].code, s.to_code(6.0));
  EXPECT_EQ(aout.outputs()[3].code, s.to_code(-2.5));
  EXPECT_EQ(aout.outputs()[4].code, 0x8001u);  // -10 V
  EXPECT_EQ(aout.outputs()[5].code, 0x7FFFu);  // +10 V
  EXPECT_EQ(aout.outputs()[6].code, 0u);       // guide, not enabled: 0 V
  EXPECT_NEAR(aout.outputs()[5].driven, 10.0, 1e-6);
}

TEST_F(RackTest, InputReactionsWhileTheRimIsOffline) {
  CardDriver& din = at(kRim2, 1);  // CDI-13, 8x DI
  const uint16_t m = din.module().number;
  for (size_t c = 0; c < 8; ++c) rack.set_source(m, c, "constant", {{"value", "1"}});
  coe::Object& reaction = module_obj(din, 0x4000, sv::kInputReaction);
  reaction.set_u(1, sv::kZeros);
  reaction.set_u(2, sv::kHoldLast);
  reaction.set_u(3, sv::kSubstitute);
  reaction.set_u(4, sv::kSubstitute);
  module_obj(din, 0x4000, sv::kInputValue).set_u(3, 1);  // channel 2 substitute 1, channel 3 0
  to_op();
  cycle();
  coe::Object& pd = module_obj(din, 0x6000, static_cast<uint8_t>(*din.card().input));
  EXPECT_EQ(pd.get_u(1), 0xFFu);
  coe::Object& status = module_obj(din, 0x4000, sv::kInputStatus);
  EXPECT_EQ(status.get_u(0), 0u);
  rack.set_rim_state(kRim2, RimState::Offline);
  cycle();
  // ch0 0, ch1 last valid 1, ch2 substitute 1, ch3 substitute 0, ch4..7 guide: 0.
  EXPECT_EQ(pd.get_u(1), 0x06u);
  EXPECT_EQ(status.get_u(0), 0xFFu);
  // A reaction written while offline applies on the next cycle.
  reaction.set_u(5, sv::kHoldLast);
  cycle();
  EXPECT_EQ(pd.get_u(1), 0x16u);
  rack.set_rim_state(kRim2, RimState::Online);
  cycle();
  EXPECT_EQ(pd.get_u(1), 0xFFu);
  EXPECT_EQ(status.get_u(0), 0u);
}

TEST_F(RackTest, OversampledInputSubstituteFillsEverySample) {
  CardDriver& ain = at(kRim2, 4);  // CAI-11/X8: 0x6nn8, 8 samples per channel
  module_obj(ain, 0x4000, sv::kInputReaction).set_u(2, sv::kSubstitute);
  module_obj(ain, 0x4000, sv::kInputValue).set_u(2, 0x1234);
  cycle();
  rack.set_rim_state(kRim2, RimState::Offline);
  cycle();
  auto raw = module_obj(ain, 0x6000, 0x8).bytes(2);
  ASSERT_EQ(raw.size(), 16u);
  for (unsigned k = 0; k < 8; ++k) EXPECT_EQ(raw[2 * k] | raw[2 * k + 1] << 8, 0x1234) << k;
  EXPECT_EQ(module_obj(ain, 0x6000, 0x8).bytes(1)[0], 0u);  // channel 0: the guide's 0
}

TEST_F(RackTest, InputReactionsOnASensorBreak) {
  CardDriver& tc = at(kRim1, 15);  // CTP-11, K
  const uint16_t m = tc.module().number;
  for (size_t c = 0; c < 3; ++c) rack.set_source(m, c, "constant", {{"value", "300"}});
  coe::Object& reaction = module_obj(tc, 0x4000, sv::kInputReaction);
  reaction.set_u(1, sv::kSubstitute);
  reaction.set_u(2, sv::kHoldLast);
  module_obj(tc, 0x4000, sv::kInputValue).set_u(1, 0x0BB8);  // 300.0 °C
  cycle();
  coe::Object& pd = module_obj(tc, 0x6000, 0x4);
  const uint64_t live = pd.get_u(2);
  EXPECT_NEAR(decode_temperature(static_cast<int16_t>(live)), 300.0, 0.1);
  for (size_t c = 0; c < 3; ++c) rack.set_sensor_open(m, c, true);
  cycle();
  EXPECT_EQ(pd.get_u(1), 0x0BB8u);
  EXPECT_EQ(pd.get_u(2), live);
  EXPECT_EQ(pd.get_u(3), 0x7FFFu);  // guide: open circuit code
  EXPECT_EQ(module_obj(tc, 0x4000, sv::kInputStatus).get_u(0), 0x07u);
  rack.set_sensor_open(m, 0, false);
  cycle();
  EXPECT_EQ(module_obj(tc, 0x4000, sv::kInputStatus).get_u(0), 0x06u);
}
