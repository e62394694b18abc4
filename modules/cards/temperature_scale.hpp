// The 16-bit temperature encoding of the thermocouple and RTD input channels.
//
// The guide does not define the temperature word, so rackcat uses (docs/MODULES.md):
//   INT16, 0.1 °C per bit, two's complement: -3276.7 °C .. +3276.6 °C,
//   e.g. 25.0 °C = 250 = 0x00FA, -40.5 °C = -405 = 0xFE6B, 1768.1 °C = 17681.
//   0x7FFF (+32767) = open circuit / sensor break (upscale burnout, as a real
//   thermocouple amplifier's burnout current drives an open input to full scale).
// Rounding is to nearest; values beyond the code range saturate at -32767/+32766 so that a
// valid reading is never confused with the open-circuit code.
#pragma once

#include <cmath>
#include <cstdint>

namespace rackcat::modules {

constexpr double kTempLsbC = 0.1;
constexpr int16_t kTempOpenCircuit = 0x7FFF;
constexpr int16_t kTempMaxCode = 32766;
constexpr int16_t kTempMinCode = -32767;

constexpr int16_t encode_temperature(double t_c) {
  const double code = t_c / kTempLsbC;
  if (!(code == code)) return kTempOpenCircuit;  // NaN: no reading
  if (code >= kTempMaxCode) return kTempMaxCode;
  if (code <= kTempMinCode) return kTempMinCode;
  // Round half away from zero without <cmath> (constexpr).
  const auto truncated = static_cast<int32_t>(code);
  const double frac = code - truncated;
  if (frac >= 0.5) return static_cast<int16_t>(truncated + 1);
  if (frac <= -0.5) return static_cast<int16_t>(truncated - 1);
  return static_cast<int16_t>(truncated);
}

constexpr double decode_temperature(int16_t code) {
  return code * kTempLsbC;
}

}  // namespace rackcat::modules
