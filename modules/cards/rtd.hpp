// Platinum RTD (Pt100) resistance per the Callendar-Van Dusen equation with the IEC 60751
// (ITS-90) coefficients, and its inverse. The RTD card (guide Table 3: 0xF022, 4 channels)
// reports temperature; the emulation turns the channel's physical temperature into ohms and
// back so that wiring faults (open/short) and lead resistance act on the resistance.
//
//   R(t) = R0 (1 + A t + B t^2)                    for 0 <= t <= 850 °C
//   R(t) = R0 (1 + A t + B t^2 + C (t - 100) t^3)  for -200 <= t < 0 °C
#pragma once

namespace rackcat::modules {

struct Cvd {
  double r0 = 100.0;  // Pt100
  double a = 3.9083e-3;
  double b = -5.775e-7;
  double c = -4.183e-12;
};

constexpr double kRtdMinC = -200.0;
constexpr double kRtdMaxC = 850.0;

// Resistance in ohms at t °C (t clamped to -200..850 °C).
double rtd_resistance(double t_c, const Cvd& k = {});
// Temperature in °C for a resistance (closed form above 0 °C, Newton iteration below).
double rtd_temperature(double ohms, const Cvd& k = {});

}  // namespace rackcat::modules
