// The 16-bit code of the ±10 V analog channels (0x6nn2/3/7/8 inputs, 0x7nn2/3 outputs and the
// 0x4nn2/0x4nn3 safe values), derived from the card's 0x3nn1:08/09 min/max voltage.
//
// The guide types the entries UINT but describes the cards as "16-bit -10 to 10" and "Open
// reads 0": an open input (0 V) reads code 0. rackcat therefore uses two's complement in the
// UINT container, symmetric about 0 V (docs/MODULES.md):
//   code = round(v * 32767 / FS), FS = max(|min V|, |max V|) = 10 V,
//   +10 V = 0x7FFF, 0 V = 0x0000, -10 V = 0x8001; 0x8000 reads as -10 V.
// Values outside min..max V saturate at the range ends.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace rackcat::modules {

struct AnalogScale {
  double min_v = -10.0;
  double max_v = 10.0;

  double full_scale() const { return std::max(std::fabs(min_v), std::fabs(max_v)); }

  uint16_t to_code(double volts) const {
    const double v = std::clamp(volts, min_v, max_v);
    const double fs = full_scale();
    if (!(fs > 0.0) || std::isnan(v)) return 0;
    // Round half away from zero (as lround, without the libm call on the cyclic path).
    const double x = v * 32767.0 / fs;
    const auto code = static_cast<int32_t>(x >= 0.0 ? x + 0.5 : x - 0.5);
    return static_cast<uint16_t>(static_cast<int16_t>(std::clamp(code, -32767, 32767)));
  }

  double to_volts(uint16_t code) const {
    const int16_t s = static_cast<int16_t>(code);
    const double v = (s == -32768 ? -32767 : s) * full_scale() / 32767.0;
    return std::clamp(v, min_v, max_v);
  }
};

}  // namespace rackcat::modules
