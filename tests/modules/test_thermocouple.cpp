// Thermocouple reference and inverse functions against the NIST ITS-90 tables
// (NIST Monograph 175 / srdata.nist.gov/its90: EMF in mV tabulated to 1 µV).
#include <gtest/gtest.h>

#include "modules/cards/temperature_scale.hpp"
#include "modules/cards/thermocouple.hpp"

using namespace rackcat::modules;

namespace {
struct Point {
  double t_c;
  double emf_mv;
};

// The tables round to 0.001 mV; allow half a digit plus float slack.
constexpr double kTableTol = 0.0006;

void check_table(TcType type, std::initializer_list<Point> points) {
  for (const Point& p : points) {
    EXPECT_NEAR(tc_emf_mv(type, p.t_c), p.emf_mv, kTableTol) << "t=" << p.t_c;
  }
}
}  // namespace

TEST(Thermocouple, TypeKMatchesNistTable) {
  check_table(TcType::K, {{-270.0, -6.458},
                          {-200.0, -5.891},
                          {-100.0, -3.554},
                          {0.0, 0.000},
                          {25.0, 1.000},
                          {100.0, 4.096},
                          {200.0, 8.138},
                          {500.0, 20.644},
                          {1000.0, 41.276},
                          {1372.0, 54.886}});
}

TEST(Thermocouple, TypeJMatchesNistTable) {
  check_table(TcType::J, {{-210.0, -8.095},
                          {-100.0, -4.633},
                          {0.0, 0.000},
                          {100.0, 5.269},
                          {200.0, 10.779},
                          {500.0, 27.393},
                          {760.0, 42.919},
                          {1000.0, 57.953},
                          {1200.0, 69.553}});
}

TEST(Thermocouple, TypeRMatchesNistTable) {
  check_table(TcType::R, {{-50.0, -0.226},
                          {0.0, 0.000},
                          {100.0, 0.647},
                          {500.0, 4.471},
                          {1000.0, 10.506},
                          {1200.0, 13.228},
                          {1500.0, 17.451},
                          {1768.1, 21.103}});
}

// NIST states the inverse polynomials' error bands (at most ±0.06 °C for K, J, R within the
// inverse ranges); a round trip t -> E -> t must stay inside them.
TEST(Thermocouple, InverseRoundTripWithinNistErrorBand) {
  for (TcType type : {TcType::K, TcType::J, TcType::R}) {
    const TcRange r = tc_inverse_range(type);
    for (double t = r.min_c; t <= r.max_c; t += 0.5) {
      EXPECT_NEAR(tc_temperature_c(type, tc_emf_mv(type, t)), t, 0.06)
          << "type " << static_cast<int>(type) << " t=" << t;
    }
  }
}

TEST(Thermocouple, InverseAtTabulatedEmf) {
  EXPECT_NEAR(tc_temperature_c(TcType::K, 4.096), 100.0, 0.05);
  EXPECT_NEAR(tc_temperature_c(TcType::J, 27.393), 500.0, 0.05);
  EXPECT_NEAR(tc_temperature_c(TcType::R, 10.506), 1000.0, 0.05);
}

TEST(Thermocouple, ColdJunctionCompensationRecoversHotJunction) {
  // 300 °C hot junction, terminals at 35 °C: the loop only sees E(300) - E(35).
  const TcMeasurement m = tc_measure(TcType::K, 300.0, 35.0, false);
  EXPECT_NEAR(m.loop_emf_mv, tc_emf_mv(TcType::K, 300.0) - tc_emf_mv(TcType::K, 35.0), 1e-12);
  EXPECT_NEAR(m.loop_emf_mv, 12.209 - 1.407, 0.0012);  // NIST: E(300)=12.209, E(35)=1.407
  EXPECT_NEAR(m.temperature_c, 300.0, 0.05);
  EXPECT_FALSE(m.open_circuit);
  // Equal temperatures: no EMF, reading = the terminal temperature.
  const TcMeasurement same = tc_measure(TcType::J, 22.0, 22.0, false);
  EXPECT_NEAR(same.loop_emf_mv, 0.0, 1e-12);
  EXPECT_NEAR(same.temperature_c, 22.0, 0.05);
}

TEST(Thermocouple, OpenCircuitIsFlaggedAndEncodedUpscale) {
  const TcMeasurement m = tc_measure(TcType::R, 800.0, 25.0, true);
  EXPECT_TRUE(m.open_circuit);
  EXPECT_EQ(encode_temperature(std::numeric_limits<double>::quiet_NaN()), kTempOpenCircuit);
}

TEST(TemperatureScale, TenthDegreePerBitSigned) {
  EXPECT_EQ(encode_temperature(25.0), 250);
  EXPECT_EQ(encode_temperature(-40.5), -405);
  EXPECT_EQ(static_cast<uint16_t>(encode_temperature(-40.5)), 0xFE6B);
  EXPECT_EQ(encode_temperature(1768.1), 17681);
  EXPECT_EQ(encode_temperature(0.04), 0);
  EXPECT_EQ(encode_temperature(0.05), 1);
  EXPECT_EQ(encode_temperature(-0.05), -1);
  EXPECT_EQ(encode_temperature(5000.0), kTempMaxCode);  // never the open-circuit code
  EXPECT_EQ(encode_temperature(-5000.0), kTempMinCode);
  EXPECT_DOUBLE_EQ(decode_temperature(-405), -40.5);
}
