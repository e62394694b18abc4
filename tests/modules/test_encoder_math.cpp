// Position, scaling, round-axis, preset and velocity arithmetic of the encoder card at its
// edges. Every expected value is worked out by hand from the encoder guide's formulas
// (the PROFINET absolute encoder user guide; section numbers of its function
// table 3.11.x) in the comment next to it, not taken from the code under test.
#include <gtest/gtest.h>

#include "mdp/encoder_settings.hpp"
#include "modules/cards/encoder_math.hpp"

namespace rackcat::modules::encoder {
namespace {

using mdp::encoder::abort_code;
using mdp::encoder::check;
using mdp::encoder::position_range;
using mdp::encoder::Refusal;
using mdp::encoder::round_axis;

// 1.1: 16-bit single-turn (65536 steps), 12-bit multi-turn (4096 turns): 2^28 = 268435456.
Hardware hw16x12() {
  return Hardware{};
}
Settings scaled(uint32_t units_per_rev, uint32_t total_range) {
  Settings s;
  s.units_per_rev = units_per_rev;
  s.total_range = total_range;
  return s;
}

TEST(EncoderMath, HardwareTotalsAreTheGuidesNumbers) {
  const Hardware hw = hw16x12();
  EXPECT_EQ(hw.steps_per_turn, 65536u);
  EXPECT_EQ(hw.turns, 4096u);
  EXPECT_EQ(hw.total(), 268435456u);  // "28 bits = 2^28 = 268435456 steps"
}

TEST(EncoderMath, UnscaledPositionWrapsAtTheTotalResolution) {
  const Hardware hw = hw16x12();
  const Settings s = scaled(65536, 268435456);  // scaling 1:1 = the physical value
  // 0.5 rev = 32768 steps.
  EXPECT_EQ(unshifted(hw, s, steps_of(hw, 0.5)), 32768u);
  // 4095 turns + 65535 steps = 4095 * 65536 + 65535 = 268435455 = 2^28 - 1, the last value.
  EXPECT_EQ(unshifted(hw, s, 268435455), 268435455u);
  // One step more is 2^28 = 0 (mod 2^28): the multi-turn counter wraps.
  EXPECT_EQ(unshifted(hw, s, 268435456), 0u);
  // One step below zero is 2^28 - 1.
  EXPECT_EQ(unshifted(hw, s, -1), 268435455u);
  // At maximum turns: 4096 turns exactly are 0 again, 4097 turns are 65536.
  EXPECT_EQ(unshifted(hw, s, steps_of(hw, 4096.0)), 0u);
  EXPECT_EQ(unshifted(hw, s, steps_of(hw, 4097.0)), 65536u);
}

TEST(EncoderMath, StepsAreTheFloorOfTheAngle) {
  const Hardware hw = hw16x12();
  // 1/65536 rev is one step; just below it is step 0; -0.25 step is step -1 (floor).
  EXPECT_EQ(steps_of(hw, 1.0 / 65536.0), 1);
  EXPECT_EQ(steps_of(hw, 0.99 / 65536.0), 0);
  EXPECT_EQ(steps_of(hw, -0.25 / 65536.0), -1);
}

TEST(EncoderMath, CodeSequenceCountsTheOtherWay) {
  const Hardware hw = hw16x12();
  Settings cw = scaled(65536, 268435456);
  Settings ccw = cw;
  ccw.ccw = true;
  // 3.11.1: CW increasing: +100 steps read 100. CCW increasing: the same rotation counts
  // down: -100 mod 2^28 = 268435356.
  EXPECT_EQ(unshifted(hw, cw, directed(cw, 100)), 100u);
  EXPECT_EQ(unshifted(hw, ccw, directed(ccw, 100)), 268435356u);
  // Turning CCW (negative steps) makes a CCW encoder count up: -100 -> 100.
  EXPECT_EQ(unshifted(hw, ccw, directed(ccw, -100)), 100u);
  // 3.11.2: without class 4 the code sequence does not act.
  ccw.class4 = false;
  EXPECT_EQ(unshifted(hw, ccw, directed(ccw, 100)), 100u);
}

TEST(EncoderMath, ScalingMeasuringUnitsPerRevolution) {
  const Hardware hw = hw16x12();
  // 3600 units per revolution (0.1 degree), 4096 turns: total range 3600 * 4096 = 14745600.
  const Settings s = scaled(3600, 14745600);
  EXPECT_FALSE(round_axis(hw, s));  // 4096 * 3600 / 14745600 = 1: an integer
  // Quarter turn: 16384 steps * 3600 / 65536 = 900.
  EXPECT_EQ(unshifted(hw, s, 16384), 900u);
  // One step: floor(1 * 3600 / 65536) = floor(0.0549) = 0; 19 steps: floor(1.0437) = 1.
  EXPECT_EQ(unshifted(hw, s, 1), 0u);
  EXPECT_EQ(unshifted(hw, s, 19), 1u);
  // Last step before the wrap: (2^28 - 1) * 3600 / 65536 = 14745599.945 -> 14745599.
  EXPECT_EQ(unshifted(hw, s, 268435455), 14745599u);
  EXPECT_EQ(unshifted(hw, s, 268435456), 0u);
  // Scaling switched off (3.11.4): the physical value, 16384.
  Settings off = s;
  off.scaling = false;
  EXPECT_EQ(unshifted(hw, off, 16384), 16384u);
  EXPECT_EQ(position_range(hw, off), 268435456u);
}

TEST(EncoderMath, RoundAxisWhenTheRangeDoesNotDivideTheTurns) {
  const Hardware hw = hw16x12();
  // 3.11.13: 100 revolutions of 1000 units: (4096 * 1000) / 100000 = 40.96, not an integer.
  const Settings s = scaled(1000, 100000);
  EXPECT_TRUE(round_axis(hw, s));
  // 128 revolutions: 4096 * 1000 / 128000 = 32, an integer: no round axis needed.
  EXPECT_FALSE(round_axis(hw, scaled(1000, 128000)));
  // Crossing the hardware's wrap at 4096 turns: turn 4095.5 is 4095.5 * 1000 = 4095500 units,
  // mod 100000 = 95500. One half turn later the shaft is at 4096 turns: on a round axis
  // 4096000 mod 100000 = 96000 (continuing), where the hardware counter alone would give 0.
  EXPECT_EQ(unshifted(hw, s, steps_of(hw, 4095.5)), 95500u);
  EXPECT_EQ(unshifted(hw, s, steps_of(hw, 4096.0)), 96000u);
  // 4100 turns: 4100000 mod 100000 = 0 (the period of 100 turns ends at 4100).
  EXPECT_EQ(unshifted(hw, s, steps_of(hw, 4100.0)), 0u);
  // Far beyond the hardware range (10^6 turns, 6.5e10 steps): 10^9 units mod 10^5 = 0, and
  // 10^6 turns + 1/4 turn: 250 units.
  EXPECT_EQ(unshifted(hw, s, steps_of(hw, 1000000.25)), 250u);
  // Backwards through zero: -0.5 turn = -500 units, mod 100000 = 99500.
  EXPECT_EQ(unshifted(hw, s, steps_of(hw, -0.5)), 99500u);
  // Without round axis (128 turns range) the hardware wrap itself is continuous:
  // 4095.5 turns = 4095500 mod 128000 = 127500; 4096 turns = 0 (= 4096000 mod 128000).
  EXPECT_EQ(unshifted(hw, scaled(1000, 128000), steps_of(hw, 4095.5)), 127500u);
  EXPECT_EQ(unshifted(hw, scaled(1000, 128000), steps_of(hw, 4096.0)), 0u);
}

TEST(EncoderMath, SmallerHardwareWrapsAtItsOwnTotal) {
  // 13-bit single-turn (8192 steps), 12-bit multi-turn: the guide's 25-bit example.
  Hardware hw;
  hw.steps_per_turn = 8192;
  hw.turns = 4096;
  EXPECT_EQ(hw.total(), 33554432u);  // 2^25
  const Settings s = scaled(8192, 33554432);
  EXPECT_EQ(unshifted(hw, s, 33554431), 33554431u);
  EXPECT_EQ(unshifted(hw, s, 33554432), 0u);
  // Single-turn only (multiturn_bits 0): 1 turn, wraps every revolution.
  hw.turns = 1;
  const Settings one = scaled(360, 360);
  EXPECT_FALSE(round_axis(hw, one));                       // 1 * 360 / 360 = 1
  EXPECT_EQ(unshifted(hw, one, steps_of(hw, 1.25)), 90u);  // 0.25 turn = 90 units
}

TEST(EncoderMath, PresetSetAndShift) {
  const Hardware hw = hw16x12();
  const Settings s = scaled(1000, 100000);
  const uint64_t range = position_range(hw, s);  // 100000
  // Set: the position is 12345, preset 500: offset = (500 - 12345) mod 100000 = 88155, and
  // (12345 + 88155) mod 100000 = 500.
  const int64_t off = preset_offset(range, 12345, 500);
  EXPECT_EQ(off, 88155);
  EXPECT_EQ(shifted(hw, s, 12345, off), 500u);
  // Moving on by 1000 units after the preset reads 1500.
  EXPECT_EQ(shifted(hw, s, 13345, off), 1500u);
  // Negative preset -1 (set): one unit before zero = 99999.
  EXPECT_EQ(shifted(hw, s, 12345, preset_offset(range, 12345, -1)), 99999u);
  // Shift by -600 from offset 88155: 87555; the position 500 becomes 500 - 600 = -100 ->
  // 99900.
  const int64_t back = shift_offset(range, off, -600);
  EXPECT_EQ(back, 87555);
  EXPECT_EQ(shifted(hw, s, 12345, back), 99900u);
  // Preset at the range's last value: 99999.
  EXPECT_EQ(shifted(hw, s, 0, preset_offset(range, 0, 99999)), 99999u);
  // Without class 4 the offset does nothing (3.11.2).
  Settings c3 = s;
  c3.class4 = false;
  EXPECT_EQ(shifted(hw, c3, 12345, off), 12345u);
}

TEST(EncoderMath, ImpossibleCombinationsAreRefusedWithTheirAbortCode) {
  const Hardware hw = hw16x12();
  // Measuring units per revolution above 65536 steps: 65537.
  Settings s = scaled(65537, 65537);
  EXPECT_EQ(check(hw, s), Refusal::UnitsPerRevAboveSteps);
  EXPECT_EQ(abort_code(check(hw, s), s, 5), coe::AbortCode::ValueTooHigh);
  // Total range above units x turns: 1000 x 4096 = 4096000; 4096001 is one too many.
  s = scaled(1000, 4096001);
  EXPECT_EQ(check(hw, s), Refusal::TotalRangeAboveTurns);
  EXPECT_EQ(abort_code(check(hw, s), s, 6), coe::AbortCode::ValueTooHigh);
  // ... the same reached by lowering the units: a combination, 0x06040043.
  EXPECT_EQ(abort_code(check(hw, s), s, 5), coe::AbortCode::ParameterIncompatible);
  EXPECT_EQ(check(hw, scaled(1000, 4096000)), Refusal::None);  // exactly at the limit
  EXPECT_EQ(check(hw, scaled(0, 10)), Refusal::UnitsPerRevZero);
  EXPECT_EQ(check(hw, scaled(10, 0)), Refusal::TotalRangeZero);
  // Preset: "If the Preset value is greater than the total resolution then error no. 0x02 comes
  // back" (Low or high limit exceeded): 100000 in a range of 100000 is too high, -100000 too low.
  s = scaled(1000, 100000);
  s.preset = 100000;
  EXPECT_EQ(abort_code(check(hw, s), s, 0x0A), coe::AbortCode::ValueTooHigh);
  s.preset = -100000;
  EXPECT_EQ(abort_code(check(hw, s), s, 0x0A), coe::AbortCode::ValueTooLow);
  s.preset = 99999;
  EXPECT_EQ(check(hw, s), Refusal::None);
  // Shrinking the range below a stored preset is a combination.
  s = scaled(1000, 1000);
  s.preset = 5000;
  EXPECT_EQ(abort_code(check(hw, s), s, 6), coe::AbortCode::ParameterIncompatible);
  // 3.11.10: 1 ... 255 failures; 3.11.11: units 0..3; 3.11.12: three filters.
  s = scaled(1000, 1000);
  s.max_life_failures = 0;
  EXPECT_EQ(check(hw, s), Refusal::LifeFailuresZero);
  s.max_life_failures = 1;
  s.velocity_unit = 4;
  EXPECT_EQ(check(hw, s), Refusal::VelocityUnit);
  s.velocity_unit = 3;
  s.velocity_filter = 3;
  EXPECT_EQ(check(hw, s), Refusal::VelocityFilter);
}

TEST(EncoderMath, VelocityUnits) {
  const Hardware hw = hw16x12();
  // 10 rev/s = 655360 steps/s. Scaled to 3600 units/rev: 36000 units/s.
  Settings s = scaled(3600, 14745600);
  s.velocity_unit = 0;
  EXPECT_DOUBLE_EQ(velocity_in_unit(hw, s, 655360.0), 36000.0);
  s.velocity_unit = 1;  // per 100 ms: 3600
  EXPECT_DOUBLE_EQ(velocity_in_unit(hw, s, 655360.0), 3600.0);
  s.velocity_unit = 2;  // per 10 ms: 360
  EXPECT_DOUBLE_EQ(velocity_in_unit(hw, s, 655360.0), 360.0);
  s.velocity_unit = 3;  // rpm: 10 rev/s * 60 = 600
  EXPECT_DOUBLE_EQ(velocity_in_unit(hw, s, 655360.0), 600.0);
  s.scaling = false;  // physical steps: 655360 steps/s
  s.velocity_unit = 0;
  EXPECT_DOUBLE_EQ(velocity_in_unit(hw, s, 655360.0), 655360.0);
}

TEST(EncoderMath, VelocityFilterRatios) {
  // 3.11.12 "Ratio between old and actual velocity value": fine 7:3 -> 0.7 * 100 + 0.3 * 200 =
  // 130; normal 96:4 -> 96 + 8 = 104; coarse 996:4 -> 99.6 + 0.8 = 100.4.
  EXPECT_DOUBLE_EQ(filter_velocity(0, 100.0, 200.0), 130.0);
  EXPECT_DOUBLE_EQ(filter_velocity(1, 100.0, 200.0), 104.0);
  EXPECT_DOUBLE_EQ(filter_velocity(2, 100.0, 200.0), 100.4);
}

}  // namespace
}  // namespace rackcat::modules::encoder
