// Pt100 Callendar-Van Dusen against the IEC 60751 reference table (ohms at °C).
#include <gtest/gtest.h>

#include "modules/cards/rtd.hpp"

using namespace rackcat::modules;

TEST(Rtd, Pt100MatchesIec60751Table) {
  struct Point {
    double t, r;
  };
  // IEC 60751 table values, 0.01 Ω resolution.
  for (const Point p :
       {Point{-200.0, 18.52}, Point{-100.0, 60.26}, Point{-50.0, 80.31}, Point{0.0, 100.00},
        Point{100.0, 138.51}, Point{200.0, 175.86}, Point{500.0, 280.98}, Point{850.0, 390.48}}) {
    EXPECT_NEAR(rtd_resistance(p.t), p.r, 0.006) << "t=" << p.t;
  }
}

TEST(Rtd, InverseRoundTrip) {
  for (double t = kRtdMinC; t <= kRtdMaxC; t += 0.25) {
    EXPECT_NEAR(rtd_temperature(rtd_resistance(t)), t, 1e-6) << "t=" << t;
  }
}

TEST(Rtd, InverseClampsOutsideRange) {
  EXPECT_DOUBLE_EQ(rtd_temperature(1000.0), kRtdMaxC);
  EXPECT_DOUBLE_EQ(rtd_temperature(5.0), kRtdMinC);
}
