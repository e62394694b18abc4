// Safe-state rule of guide §2.5 (Tables 7-10) for every combination of enable, action,
// configured value and current output, on every channel position.
#include <gtest/gtest.h>

#include "modules/cards/analog_scale.hpp"
#include "modules/cards/safe_state.hpp"
#include "modules/rack/events.hpp"

using namespace rackcat::modules;

TEST(SafeState, DigitalEveryCombinationEveryChannel) {
  for (unsigned ch = 0; ch < 16; ++ch) {
    for (unsigned combo = 0; combo < 16; ++combo) {
      const uint32_t enable = (combo & 1) << ch;
      const uint32_t action = ((combo >> 1) & 1) << ch;
      const uint32_t value = ((combo >> 2) & 1) << ch;
      const uint32_t current = ((combo >> 3) & 1) << ch;
      uint32_t expect = 0;  // disabled: de-energised
      if (enable && action) expect = value;
      if (enable && !action) expect = current;
      EXPECT_EQ(digital_safe_state(current, enable, action, value, 16), expect)
          << "channel " << ch << " combo " << combo;
    }
  }
}

TEST(SafeState, DigitalChannelsAreIndependent) {
  // ch0 hold (current 1), ch1 set 1, ch2 set 0 (current 1), ch3 disabled (current 1).
  const uint32_t out = digital_safe_state(/*current*/ 0b1101, /*enable*/ 0b0111,
                                          /*action*/ 0b0110, /*value*/ 0b1010, 4);
  EXPECT_EQ(out, 0b0011u);
  // Bits above the channel count never appear.
  EXPECT_EQ(digital_safe_state(0xFFFF, 0xFFFF, 0, 0, 8), 0xFFu);
}

TEST(SafeState, AnalogEveryCombination) {
  for (unsigned ch = 0; ch < 16; ++ch) {
    for (unsigned combo = 0; combo < 4; ++combo) {
      const uint32_t enable = (combo & 1) << ch;
      const uint32_t action = ((combo >> 1) & 1) << ch;
      const uint16_t got = analog_safe_state(0x1234, enable, action, 0x7FFF, ch);
      const uint16_t expect = !enable ? 0 : (action ? 0x7FFF : 0x1234);
      EXPECT_EQ(got, expect) << "channel " << ch << " combo " << combo;
    }
  }
}

TEST(AnalogScale, SymmetricTwosComplementOverMinMaxVoltage) {
  const AnalogScale s{-10.0, 10.0};
  EXPECT_EQ(s.to_code(0.0), 0x0000);
  EXPECT_EQ(s.to_code(10.0), 0x7FFF);
  EXPECT_EQ(s.to_code(-10.0), 0x8001);
  EXPECT_EQ(s.to_code(5.0), 16384);    // 16383.5 rounds away from zero
  EXPECT_EQ(s.to_code(25.0), 0x7FFF);  // saturates at max voltage
  EXPECT_EQ(s.to_code(-25.0), 0x8001);
  EXPECT_DOUBLE_EQ(s.to_volts(0x7FFF), 10.0);
  EXPECT_DOUBLE_EQ(s.to_volts(0x8000), -10.0);
  EXPECT_NEAR(s.to_volts(s.to_code(3.3)), 3.3, 10.0 / 32767);
}

TEST(Fans, GuideThresholdsOnDeviationFromNominal) {
  EXPECT_EQ(fan_level_bits(0.0), 0u);
  EXPECT_EQ(fan_level_bits(-14.9), 0u);
  EXPECT_EQ(fan_level_bits(-15.0), 1u);
  EXPECT_EQ(fan_level_bits(-30.0), 3u);
  EXPECT_EQ(fan_level_bits(-50.0), 7u);
  EXPECT_EQ(fan_level_bits(-100.0), 7u);
  EXPECT_EQ(fan_level_bits(+40.0), 0u);
}
