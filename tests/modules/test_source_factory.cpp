// Source descriptions as the rack file and the control API give them.
#include <gtest/gtest.h>

#include <ctime>

#include "modules/cards/analog_scale.hpp"
#include "modules/signals/signal_source.hpp"
#include "modules/signals/source_factory.hpp"
#include "modules/signals/state_space_plant.hpp"

using namespace rackcat::modules;

namespace {
SourceContext context(double* out) {
  SourceContext ctx;
  ctx.output = [out](uint8_t rim, uint8_t slot, uint8_t ch) {
    if (rim == 1 && slot == 11 && ch == 0) return OutputRef{out, "rim1.slot11.out0"};
    return OutputRef{nullptr, "no such output"};
  };
  return ctx;
}
}  // namespace

TEST(SourceFactory, BuildsEveryKindFromTextParameters) {
  double out = 0;
  SourceContext ctx = context(&out);
  EXPECT_DOUBLE_EQ(make_source("constant", {{"value", "2.5"}}, ctx)->sample(0), 2.5);
  auto sine = make_source("sine", {{"amplitude", "5"}, {"period_s", "1"}}, ctx);
  EXPECT_NEAR(sine->sample(0.25), 5.0, 1e-12);
  auto ramp = make_source("ramp", {{"from", "-10"}, {"to", "10"}, {"period_s", "10"}}, ctx);
  EXPECT_DOUBLE_EQ(ramp->sample(5.0), 0.0);
  auto noise = make_source("noise", {{"mean", "0"}, {"stddev", "0.01"}, {"seed", "7"}}, ctx);
  EXPECT_NEAR(noise->sample(0), 0.0, 0.1);
  auto loop = make_source("loopback", {{"rim", "1"}, {"slot", "11"}, {"channel", "0"}}, ctx);
  out = 1.0;
  EXPECT_DOUBLE_EQ(loop->sample(0), 1.0);
}

TEST(SourceFactory, RejectsBadDescriptionsWithTheReason) {
  double out = 0;
  SourceContext ctx = context(&out);
  auto reason = [&](std::string_view kind, SourceParams p) {
    try {
      make_source(kind, p, ctx);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(reason("square", {}).find("unknown source 'square'"), std::string::npos);
  EXPECT_NE(reason("sine", {{"amplitude", "x"}, {"period_s", "1"}}).find("'amplitude'"),
            std::string::npos);
  EXPECT_NE(reason("sine", {{"period_s", "1"}}).find("missing parameter 'amplitude'"),
            std::string::npos);
  EXPECT_NE(reason("constant", {{"valeu", "1"}}).find("unknown parameter 'valeu'"),
            std::string::npos);
  // A misspelt parameter is named as such before anything reports a missing one.
  EXPECT_NE(reason("sine", {{"amplitud", "5"}}).find("sine: unknown parameter 'amplitud'"),
            std::string::npos);
  EXPECT_NE(
      reason("loopback", {{"rim", "1"}, {"slot", "12"}, {"channel", "0"}}).find("no such output"),
      std::string::npos);
  EXPECT_NE(reason("noise", {{"stddev", "-1"}}).find("stddev"), std::string::npos);
}

TEST(SourceFactory, MatrixText) {
  const MatrixText m = parse_matrix("1 2; 3 4", "a");
  EXPECT_EQ(m.rows, 2u);
  EXPECT_EQ(m.cols, 2u);
  EXPECT_EQ(m.values, (std::vector<double>{1, 2, 3, 4}));
  EXPECT_THROW(parse_matrix("1 2; 3", "a"), std::invalid_argument);
  EXPECT_THROW(parse_matrix("1 x", "a"), std::invalid_argument);
}

TEST(SourceFactory, PlantBoundToAnOutput) {
  double heater = 10.0;  // volts on an analog output
  SourceContext ctx = context(&heater);
  std::unique_ptr<StateSpacePlant> plant;
  ctx.plant = [&](const std::string&, const SourceParams& p) -> StateSpacePlant& {
    if (!plant) {
      plant = make_plant(p, 0.01, [&](const std::string& ref) {
        return ref == "1.11.0" ? OutputRef{&heater, ref} : OutputRef{nullptr, "bad"};
      });
    }
    return *plant;
  };
  // Thermal lag: T' = (-T + 20 + 8 u) / 2 around 20 degC ambient expressed as x = T - 20.
  auto src = make_source("plant",
                         {{"plant", "oven"},
                          {"a", "-0.5"},
                          {"b", "4"},
                          {"c", "1"},
                          {"inputs", "1.11.0"},
                          {"output", "0"}},
                         ctx);
  for (int k = 0; k < 3000; ++k) plant->step();  // 30 s = 15 time constants
  EXPECT_NEAR(src->sample(0), 80.0, 1e-3);       // steady state 8 * 10 V
}

// The clock source is the time stamp the CAN input-age measurement decodes (docs/CAN.md): the
// ±10 V code must count ticks of CLOCK_MONOTONIC exactly through the analog scaling.
TEST(SourceFactory, ClockSourceCodesMonotonicTicksThroughTheAnalogScale) {
  double out = 0;
  SourceContext ctx = context(&out);
  const ClockSource clock(10.0);
  EXPECT_EQ(clock.code_at(0), -32767);
  EXPECT_EQ(clock.code_at(9'999), -32767);
  EXPECT_EQ(clock.code_at(10'000), -32766);
  EXPECT_EQ(clock.code_at(int64_t{65534} * 10'000), 32767);
  EXPECT_EQ(clock.code_at(int64_t{65535} * 10'000), -32767);  // wraps over 65535 codes

  auto src = make_source("clock", {{"tick_us", "10"}}, ctx);
  const AnalogScale scale;
  auto now_ns = [] {
    timespec ts{};
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
  };
  const int64_t before = now_ns();
  const auto code = static_cast<int16_t>(scale.to_code(src->sample(0)));
  const int64_t after = now_ns();
  const int lo = clock.code_at(before), hi = clock.code_at(after);
  if (lo <= hi) {
    EXPECT_GE(code, lo);
    EXPECT_LE(code, hi);
  } else {  // wrapped between the two reads
    EXPECT_TRUE(code >= lo || code <= hi);
  }
  EXPECT_THROW(make_source("clock", {{"tick_us", "0"}}, ctx), std::invalid_argument);
}
