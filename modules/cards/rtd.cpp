#include "modules/cards/rtd.hpp"

#include <algorithm>
#include <cmath>

namespace rackcat::modules {

double rtd_resistance(double t, const Cvd& k) {
  t = std::clamp(t, kRtdMinC, kRtdMaxC);
  double f = 1.0 + k.a * t + k.b * t * t;
  if (t < 0.0) f += k.c * (t - 100.0) * t * t * t;
  return k.r0 * f;
}

double rtd_temperature(double ohms, const Cvd& k) {
  const double ratio = ohms / k.r0;
  // Above 0 °C the quadratic solves exactly: B t^2 + A t + (1 - R/R0) = 0.
  const double disc = k.a * k.a - 4.0 * k.b * (1.0 - ratio);
  double t = (-k.a + std::sqrt(std::max(disc, 0.0))) / (2.0 * k.b);
  if (ratio >= 1.0) return std::min(t, kRtdMaxC);
  // Below 0 °C the C term makes it a quartic; the quadratic root is within ~0.05 °C, a few
  // Newton steps converge to machine precision.
  t = std::max(t, kRtdMinC);
  for (int i = 0; i < 8; ++i) {
    const double f = k.r0 * (1.0 + k.a * t + k.b * t * t + k.c * (t - 100.0) * t * t * t) - ohms;
    const double df = k.r0 * (k.a + 2.0 * k.b * t + k.c * (4.0 * t * t * t - 300.0 * t * t));
    const double step = f / df;
    t -= step;
    if (std::fabs(step) < 1e-9) break;
  }
  return std::clamp(t, kRtdMinC, 0.0);
}

}  // namespace rackcat::modules
