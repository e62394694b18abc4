// Drivers behind a real mdp::Device: process data in and out, loopbacks, oversampling,
// temperatures, power-on rule and safe states.
#include <chrono>
#include <cstdint>

#include "base/cache_line_allocator.hpp"
#include "base/round_time.hpp"
#include "modules/cards/analog_scale.hpp"
#include "modules/cards/temperature_scale.hpp"
#include "rack_fixture.hpp"

using namespace rackcat;
using namespace rackcat::modules;
using namespace rackcat::modules::testing;

namespace {
// Default rack (examples/default-rack.yaml): RIM 1 slot 1 CDO-10 -> slot 2 CDI-10 loopback,
// slot 11 CAO-15 -> slot 12 CAI-11 loopback, slot 4 CIO-10, 15/16/17 thermocouples K/J/R,
// 18 RTD, 19 UART; RIM 2 slot 3 CDI-10/X8, slot 4 CAI-11/X8, slot 7 CDO-10.
constexpr uint8_t kRim1 = 1, kRim2 = 2;
}  // namespace

TEST_F(RackTest, DigitalOutputsReadBackThroughLoopbackInputInOp) {
  CardDriver& dout = at(kRim1, 1);
  CardDriver& din = at(kRim1, 2);
  to_op();
  module_obj(dout, 0x7000, 0x0).set_u(1, 0xA5C3);
  cycle();
  EXPECT_EQ(module_obj(din, 0x6000, 0x0).get_u(1), 0xA5C3u);
  EXPECT_EQ(dout.outputs()[0].driven, 1.0);
  EXPECT_EQ(dout.outputs()[2].driven, 0.0);
}

TEST_F(RackTest, OutputsAreNotDrivenBeforeTheFirstValidOutputData) {
  CardDriver& dout = at(kRim1, 1);
  CardDriver& din = at(kRim1, 2);
  go(EsmState::Init, EsmState::PreOp);
  go(EsmState::PreOp, EsmState::SafeOp);
  module_obj(dout, 0x7000, 0x0).set_u(1, 0xFFFF);
  cycle();  // SAFEOP: output data is not valid yet
  cycle();
  EXPECT_FALSE(rack.outputs_valid());
  EXPECT_EQ(module_obj(din, 0x6000, 0x0).get_u(1), 0u);
  for (const auto& o : dout.outputs()) EXPECT_EQ(o.driven, 0.0);
  go(EsmState::SafeOp, EsmState::Op);
  cycle();
  EXPECT_TRUE(rack.outputs_valid());
  EXPECT_EQ(module_obj(din, 0x6000, 0x0).get_u(1), 0xFFFFu);
}

TEST_F(RackTest, DigitalSafeStatesOnLeavingOp) {
  CardDriver& dout = at(kRim1, 1);
  CardDriver& din = at(kRim1, 2);
  coe::Object& safe = module_obj(dout, 0x4000, 0x0);  // 0x4nn0, 16 channels (Table 7)
  safe.set_u(1, 0x00FF);                              // enable channels 0..7
  safe.set_u(2, 0x000F);                              // 0..3 set value, 4..7 hold
  safe.set_u(3, 0x0005);                              // value for 0..3: 1,0,1,0
  for (EsmState target : {EsmState::SafeOp, EsmState::PreOp, EsmState::Init}) {
    to_op();
    module_obj(dout, 0x7000, 0x0).set_u(1, 0xFFFF);
    cycle();
    go(EsmState::Op, target);
    // 0..3 value 0101, 4..7 hold 1111, 8..15 not enabled: de-energised.
    EXPECT_EQ(dout.outputs()[0].driven, 1.0);
    EXPECT_EQ(dout.outputs()[1].driven, 0.0);
    EXPECT_EQ(dout.outputs()[7].driven, 1.0);
    EXPECT_EQ(dout.outputs()[8].driven, 0.0);
    if (target == EsmState::SafeOp) {
      cycle();  // inputs still run in SAFEOP and see the wires
      EXPECT_EQ(module_obj(din, 0x6000, 0x0).get_u(1), 0x00F5u);
    }
    // New output data outside OP does not reach the terminals.
    module_obj(dout, 0x7000, 0x0).set_u(1, 0x0000);
    cycle();
    EXPECT_EQ(dout.outputs()[7].driven, 1.0);
    if (target != EsmState::Init) go(target, EsmState::Init);
  }
}

TEST_F(RackTest, EightChannelDigitalSafeStateUsesUsint) {
  CardDriver& relay = at(kRim1, 6);  // CRS-10, 0x4nn1 (Table 8)
  coe::Object& safe = module_obj(relay, 0x4000, 0x1);
  safe.set_u(1, 0xF0);
  safe.set_u(2, 0xC0);
  safe.set_u(3, 0x40);
  to_op();
  module_obj(relay, 0x7000, 0x1).set_u(1, 0xFF);
  cycle();
  go(EsmState::Op, EsmState::SafeOp);
  // ch 7,6 set value (0,1); ch 5,4 hold (1,1); ch 3..0 disabled (0).
  uint32_t word = 0;
  for (size_t i = 0; i < relay.outputs().size(); ++i)
    word |= (relay.outputs()[i].driven >= 0.5 ? 1u : 0u) << i;
  EXPECT_EQ(word, 0x70u);
}

TEST_F(RackTest, WatchdogAppliesSafeStateAndRaisesPdTimeout) {
  CardDriver& aout = at(kRim1, 11);  // CAO-15, 0x4nn2 (Table 9)
  coe::Object& safe = module_obj(aout, 0x4000, 0x2);
  safe.set_u(1, 0x03);  // channels 0, 1 enabled
  safe.set_u(2, 0x01);  // channel 0 set value, channel 1 hold
  const AnalogScale s{-10, 10};
  safe.set_u(3, s.to_code(-2.5));  // value[0]
  to_op();
  coe::Object& out = module_obj(aout, 0x7000, 0x2);
  out.set_u(1, s.to_code(7.0));
  out.set_u(2, s.to_code(3.0));
  out.set_u(3, s.to_code(1.0));
  cycle();
  drain_emergencies();
  device.watchdog_expired();
  EXPECT_NEAR(aout.outputs()[0].driven, -2.5, 1e-3);
  EXPECT_NEAR(aout.outputs()[1].driven, 3.0, 1e-3);
  EXPECT_EQ(aout.outputs()[2].driven, 0.0);  // not enabled: 0 V
  EXPECT_TRUE(has_code(drain_emergencies(), 0x8110));
  // The ESM then drops to SAFEOP: the same substitute values.
  go(EsmState::Op, EsmState::SafeOp);
  EXPECT_NEAR(aout.outputs()[0].driven, -2.5, 1e-3);
  EXPECT_NEAR(aout.outputs()[1].driven, 3.0, 1e-3);
}

TEST_F(RackTest, SixteenChannelAnalogSafeStateValues) {
  CardDriver& aout = at(kRim1, 13);  // CAO-17, 0x4nn3 (Table 10)
  coe::Object& safe = module_obj(aout, 0x4000, 0x3);
  const AnalogScale s{-10, 10};
  safe.set_u(1, 0x8000);
  safe.set_u(2, 0x8000);
  safe.set_u(3 + 15, s.to_code(9.0));  // value[15] at subindex 0x12
  to_op();
  module_obj(aout, 0x7000, 0x3).set_u(16, s.to_code(-9.0));
  cycle();
  EXPECT_NEAR(aout.outputs()[15].driven, -9.0, 1e-3);
  go(EsmState::Op, EsmState::SafeOp);
  EXPECT_NEAR(aout.outputs()[15].driven, 9.0, 1e-3);
}

TEST_F(RackTest, AnalogOutputLoopsBackToAnalogInputWithTheSameCode) {
  CardDriver& aout = at(kRim1, 11);
  CardDriver& ain = at(kRim1, 12);
  to_op();
  const AnalogScale s{-10, 10};
  module_obj(aout, 0x7000, 0x2).set_u(1, s.to_code(4.2));
  module_obj(aout, 0x7000, 0x2).set_u(8, s.to_code(-10.0));
  cycle();
  EXPECT_EQ(module_obj(ain, 0x6000, 0x2).get_u(1), s.to_code(4.2));
  EXPECT_EQ(module_obj(ain, 0x6000, 0x2).get_u(8), 0x8001u);
}

TEST_F(RackTest, AnalogInputSourcesFromTheRackFile) {
  CardDriver& ain = at(kRim1, 14);  // CAI-15 with sine/ramp/constant/noise on 0..3
  cycle();
  EXPECT_EQ(module_obj(ain, 0x6000, 0x3).get_u(3), AnalogScale{}.to_code(2.5));
  EXPECT_NE(ain.source(0).describe().find("sine"), std::string::npos);
}

TEST_F(RackTest, OversampledDigitalInputSpreadsEightSamplesOverTheCycle) {
  CardDriver& din = at(kRim2, 3);  // CDI-10/X8: 0x6nn5, 8 x UINT
  // 1000 V/s from 0: sample k of the first 1 ms cycle sees (k+1)/8 -> 1 from k = 3.
  rack.set_source(din.module().number, 0, "ramp",
                  {{"from", "0"}, {"to", "8"}, {"period_s", "0.008"}});
  cycle();
  auto raw = module_obj(din, 0x6000, 0x5).bytes(1);
  ASSERT_EQ(raw.size(), 16u);
  for (unsigned k = 0; k < 8; ++k) {
    const unsigned word = raw[2 * k] | raw[2 * k + 1] << 8;
    EXPECT_EQ(word & 1u, k >= 3 ? 1u : 0u) << "sample " << k;
  }
}

TEST_F(RackTest, OversampledAnalogInputCarriesEightSamples) {
  CardDriver& ain = at(kRim2, 4);  // CAI-11/X8: 0x6nn8
  rack.set_source(ain.module().number, 2, "ramp",
                  {{"from", "0"}, {"to", "8"}, {"period_s", "0.008"}});
  cycle();
  auto raw = module_obj(ain, 0x6000, 0x8).bytes(3);
  ASSERT_EQ(raw.size(), 16u);
  const AnalogScale s{-10, 10};
  for (unsigned k = 0; k < 8; ++k) {
    EXPECT_EQ(raw[2 * k] | raw[2 * k + 1] << 8, s.to_code((k + 1) * 0.125)) << k;
  }
}

TEST_F(RackTest, ThermocouplesReportTemperatureAndLoopOhms) {
  struct Case {
    uint8_t slot;
    double t;
  };
  for (Case c : {Case{15, 300.0}, Case{16, 500.0}, Case{17, 1500.0}}) {  // K, J, R
    CardDriver& tc = at(kRim1, c.slot);
    rack.set_source(tc.module().number, 0, "constant", {{"value", std::to_string(c.t)}});
    rack.set_loop_ohms(tc.module().number, 1, 37.4);
    cycle();
    const auto code = static_cast<int16_t>(module_obj(tc, 0x6000, 0x4).get_u(1));
    EXPECT_NEAR(decode_temperature(code), c.t, 0.1) << "slot " << int(c.slot);
    EXPECT_EQ(module_obj(tc, 0x5000, 0x4).get_u(2), 37u);  // 0x5nn4 Ohms[2]
    rack.set_sensor_open(tc.module().number, 0, true);
    cycle();
    EXPECT_EQ(module_obj(tc, 0x6000, 0x4).get_u(1), 0x7FFFu);
    EXPECT_EQ(module_obj(tc, 0x5000, 0x4).get_u(1), 0xFFFFu);
  }
}

TEST_F(RackTest, RtdReportsTemperature) {
  CardDriver& rtd = at(kRim1, 18);
  rack.set_source(rtd.module().number, 3, "constant", {{"value", "-120.5"}});
  cycle();
  EXPECT_EQ(static_cast<int16_t>(module_obj(rtd, 0x6000, 0x9).get_u(4)), -1205);
  rack.set_sensor_open(rtd.module().number, 3, true);
  cycle();
  EXPECT_EQ(module_obj(rtd, 0x6000, 0x9).get_u(4), 0x7FFFu);
}

TEST_F(RackTest, E84CardReadsBackItsOutputs) {
  CardDriver& dio = at(kRim1, 4);  // CIO-10: DIOx8 sub 1 inputs, sub 2 read-back
  rack.set_source(dio.module().number, 5, "constant", {{"value", "1"}});
  to_op();
  module_obj(dio, 0x7000, 0x1).set_u(1, 0x3C);
  cycle();
  EXPECT_EQ(module_obj(dio, 0x6000, 0xC).get_u(1), 0x20u);
  EXPECT_EQ(module_obj(dio, 0x6000, 0xC).get_u(2), 0x3Cu);
}

TEST_F(RackTest, ForceGuidedRelayFeedbackFollowsTheContacts) {
  CardDriver& relay = at(kRim1, 3);  // CRS-14: DOUTx4 + DINx4 feedback
  to_op();
  module_obj(relay, 0x7000, 0xB).set_u(1, 0x9);
  cycle();
  EXPECT_EQ(module_obj(relay, 0x6000, 0xB).get_u(1), 0x9u);
}

TEST_F(RackTest, InvertedInputsReportLowAsOne) {
  CardDriver& din = at(kRim1, 7);  // CDI-12
  rack.set_source(din.module().number, 0, "constant", {{"value", "1"}});
  cycle();
  EXPECT_EQ(module_obj(din, 0x6000, 0x0).get_u(1), 0xFFFEu);
}

TEST_F(RackTest, PlantDrivenByAnAnalogOutputMovesAThermocouple) {
  // Oven: x' = -x/10 + 5 u (u = heater volts), read in °C by thermocouple channel 5.
  CardDriver& tc = at(kRim1, 15);
  rack.set_source(tc.module().number, 5, "plant",
                  {{"plant", "oven"},
                   {"a", "-0.1"},
                   {"b", "5"},
                   {"c", "1"},
                   {"inputs", "1.11.0"},
                   {"output", "0"}});
  rack.set_source(tc.module().number, 6, "plant", {{"plant", "oven"}});
  to_op();
  module_obj(at(kRim1, 11), 0x7000, 0x2).set_u(1, AnalogScale{}.to_code(2.0));
  for (int k = 0; k < 10000; ++k) cycle();               // 10 s = 1 time constant
  const double expect = 100.0 * (1.0 - std::exp(-1.0));  // 5*2/0.1 = 100 steady state
  const auto code = static_cast<int16_t>(module_obj(tc, 0x6000, 0x4).get_u(6));
  EXPECT_NEAR(decode_temperature(code), expect, 0.2);
  EXPECT_EQ(module_obj(tc, 0x6000, 0x4).get_u(7), module_obj(tc, 0x6000, 0x4).get_u(6));
}

// Without a clock of its own the rack samples at the firmware round's time (base/round_time.hpp,
// one clock read per round for every slave); outside a round it reads the clock.
TEST(RackClock, DefaultClockIsTheFirmwareRoundsTime) {
  mdp::DeviceOptions options;
  options.state_dir = ::testing::TempDir() + "rack_clock";
  options.load_stored_parameters = false;
  mdp::Device device(mdp::default_rack(), options);
  Rack rack(device);
  double in_round = 0.0;
  {
    const base::RoundTime::Scope round;
    in_round = rack.now();
    const auto t0 = std::chrono::steady_clock::now();
    while (std::chrono::steady_clock::now() == t0) {
    }
    EXPECT_EQ(rack.now(), in_round);
  }
  const auto t1 = std::chrono::steady_clock::now();
  while (std::chrono::steady_clock::now() == t1) {
  }
  EXPECT_GT(rack.now(), in_round);
}

// A card's channel arrays start on a cache line (base/cache_line_allocator.hpp): 8 channels of
// 32 bytes are 4 lines for the cyclic path, not 5 (issue 16).
TEST_F(RackTest, ChannelArraysStartOnACacheLine) {
  size_t checked = 0;
  for (uint16_t m = 1; rack.driver(m) != nullptr; ++m) {
    const CardDriver& d = *rack.driver(m);
    for (const void* p : {static_cast<const void*>(d.inputs().data()),
                          static_cast<const void*>(d.outputs().data())}) {
      if (p == nullptr) continue;
      EXPECT_EQ(reinterpret_cast<uintptr_t>(p) % base::kCacheLine, 0u) << "module " << m;
      ++checked;
    }
  }
  EXPECT_GT(checked, 10u);
}
