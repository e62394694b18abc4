// Signal models: what a user configures on an input channel is what the channel reads.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>

#include "modules/signals/signal_source.hpp"
#include "modules/signals/state_space_plant.hpp"

using namespace rackcat::modules;

TEST(Sources, ConstantRampSine) {
  ConstantSource c(3.5);
  EXPECT_DOUBLE_EQ(c.sample(0.0), 3.5);
  EXPECT_DOUBLE_EQ(c.sample(100.0), 3.5);

  RampSource r(-10.0, 10.0, 2.0);
  EXPECT_DOUBLE_EQ(r.sample(0.0), -10.0);
  EXPECT_DOUBLE_EQ(r.sample(1.0), 0.0);
  EXPECT_DOUBLE_EQ(r.sample(1.5), 5.0);
  EXPECT_DOUBLE_EQ(r.sample(2.0), -10.0);  // sawtooth restarts
  EXPECT_THROW(RampSource(0, 1, 0), std::invalid_argument);

  SineSource s(2.0, 0.5, 1.0);
  EXPECT_NEAR(s.sample(0.0), 1.0, 1e-12);
  EXPECT_NEAR(s.sample(0.5), 3.0, 1e-12);  // quarter period of 2 s
  EXPECT_NEAR(s.sample(1.5), -1.0, 1e-12);
}

TEST(Sources, NoiseIsReproducibleFromSeedWithRequestedMoments) {
  NoiseSource a(1.0, 0.5, 42), b(1.0, 0.5, 42), c(1.0, 0.5, 43);
  bool differs = false;
  double sum = 0, sum2 = 0;
  constexpr int n = 200000;
  for (int i = 0; i < n; ++i) {
    const double va = a.sample(0), vb = b.sample(0), vc = c.sample(0);
    ASSERT_EQ(va, vb);
    differs |= va != vc;
    sum += va;
    sum2 += va * va;
  }
  EXPECT_TRUE(differs);
  const double mean = sum / n;
  const double var = sum2 / n - mean * mean;
  EXPECT_NEAR(mean, 1.0, 0.01);
  EXPECT_NEAR(std::sqrt(var), 0.5, 0.01);
}

namespace {
std::string write_temp(const char* name, const char* text) {
  std::string path = testing::TempDir() + name;
  std::ofstream(path) << text;
  return path;
}
}  // namespace

TEST(Sources, ReplayInterpolatesLoopsOrHolds) {
  const std::string path =
      write_temp("replay_ok.csv", "time_s,value\n# comment\n0,0\n1,10\n2, -10\r\n");
  auto hold = ReplaySource::from_csv(path, false);
  EXPECT_DOUBLE_EQ(hold->sample(0.0), 0.0);
  EXPECT_DOUBLE_EQ(hold->sample(0.25), 2.5);
  EXPECT_DOUBLE_EQ(hold->sample(1.5), 0.0);
  EXPECT_DOUBLE_EQ(hold->sample(5.0), -10.0);
  auto loop = ReplaySource::from_csv(path, true);
  EXPECT_DOUBLE_EQ(loop->sample(0.5), 5.0);
  EXPECT_DOUBLE_EQ(loop->sample(2.5), 5.0);  // period 2 s
  EXPECT_DOUBLE_EQ(loop->sample(3.0), 10.0);
}

TEST(Sources, ReplayRejectsBadFilesWithFileAndLine) {
  const std::string bad = write_temp("replay_bad.csv", "0,1\n1,x\n");
  try {
    ReplaySource::from_csv(bad, false);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("replay_bad.csv:2:"), std::string::npos) << e.what();
  }
  const std::string order = write_temp("replay_order.csv", "0,1\n1,2\n1,3\n");
  EXPECT_THROW(ReplaySource::from_csv(order, false), std::runtime_error);
  EXPECT_THROW(ReplaySource::from_csv(testing::TempDir() + "missing.csv", false),
               std::runtime_error);
  const std::string empty = write_temp("replay_empty.csv", "time,value\n");
  EXPECT_THROW(ReplaySource::from_csv(empty, false), std::runtime_error);
}

TEST(Sources, LoopbackFollowsOutput) {
  double out = 0.0;
  LoopbackSource l(&out, "m3.ch0", 2.0, 1.0);
  EXPECT_DOUBLE_EQ(l.sample(0), 1.0);
  out = 4.0;
  EXPECT_DOUBLE_EQ(l.sample(0), 9.0);
}

// First-order lag y' = (K u - y) / tau: the discretised step response equals the analytic
// K (1 - e^(-t/tau)) at every sample instant (ZOH is exact for a constant input).
TEST(Plant, FirstOrderStepMatchesAnalytic) {
  const double tau = 0.5, gain = 3.0, dt = 0.001;
  Eigen::MatrixXd a(1, 1), b(1, 1), c(1, 1);
  a << -1.0 / tau;
  b << gain / tau;
  c << 1.0;
  StateSpacePlant p(a, b, c, Eigen::MatrixXd(), dt);
  double u = 1.0;
  p.bind_input(0, &u);
  for (int k = 0; k <= 3000; ++k) {
    p.step();  // y is the output at t = k dt
    EXPECT_NEAR(p.output(0), gain * (1.0 - std::exp(-k * dt / tau)), 1e-9) << "k=" << k;
  }
}

// Underdamped mass-spring-damper x'' + 2 z w x' + w^2 x = w^2 u against the analytic step
// response 1 - e^(-z w t) (cos(wd t) + z/sqrt(1-z^2) sin(wd t)).
TEST(Plant, SecondOrderStepMatchesAnalytic) {
  const double w = 2.0 * std::numbers::pi * 2.0, z = 0.2, dt = 0.0005;
  Eigen::MatrixXd a(2, 2), b(2, 1), c(1, 2);
  a << 0, 1, -w * w, -2 * z * w;
  b << 0, w * w;
  c << 1, 0;
  StateSpacePlant p(a, b, c, Eigen::MatrixXd(), dt);
  p.set_input(0, 1.0);
  const double wd = w * std::sqrt(1 - z * z);
  for (int k = 0; k <= 4000; ++k) {
    p.step();
    const double t = k * dt;
    const double expect =
        1.0 -
        std::exp(-z * w * t) * (std::cos(wd * t) + z / std::sqrt(1 - z * z) * std::sin(wd * t));
    EXPECT_NEAR(p.output(0), expect, 1e-8) << "t=" << t;
  }
}

TEST(Plant, FeedthroughAndPlantSource) {
  Eigen::MatrixXd a(1, 1), b(1, 1), c(2, 1), d(2, 1);
  a << -1;
  b << 1;
  c << 1, 0;
  d << 0, 5;
  StateSpacePlant p(a, b, c, d, 0.01);
  double u = 2.0;
  p.bind_input(0, &u);
  p.step();
  PlantSource direct(p, 1, "heater");
  EXPECT_DOUBLE_EQ(direct.sample(0), 10.0);
  EXPECT_THROW(PlantSource(p, 2, "heater"), std::invalid_argument);
}

TEST(Plant, RejectsInconsistentDimensions) {
  Eigen::MatrixXd a(2, 2), b(1, 1), c(1, 2);
  a.setZero();
  b.setZero();
  c.setZero();
  EXPECT_THROW(StateSpacePlant(a, b, c, Eigen::MatrixXd(), 0.001), std::invalid_argument);
  Eigen::MatrixXd b2 = Eigen::MatrixXd::Zero(2, 1);
  EXPECT_THROW(StateSpacePlant(a, b2, c, Eigen::MatrixXd(), 0.0), std::invalid_argument);
}
