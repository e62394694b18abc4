// The encoder card in a rack, cycle by cycle: telegram layout, preset through the control word
// (set, shift, while moving), the master's sign-of-life, injected faults with their error code,
// Emergency and 0x10F3 message, and refused parameter combinations. Expected numbers are worked
// out from the encoder guide's formulas in the comments.
#include <gtest/gtest.h>

#include <cstring>

#include "coe/bits.hpp"
#include "mdp/encoder_settings.hpp"
#include "modules/cards/encoder_driver.hpp"
#include "modules/rack/rack.hpp"
#include "tests/modules/rack_fixture.hpp"
#include "tests/support/allocation_counter.hpp"

namespace rackcat::modules::testing {
namespace {

namespace enc = mdp::encoder;

// RIM 1: slot 1 encoder (module 1) on a shaft at 10 rev/s; slot 2 an 8-channel digital input.
constexpr const char* kRack = R"(
rims:
  - rim: 1
    type: 6-slot
    slots:
      - slot: 1
        card: CAE-10
        channels:
          - {channel: 0, source: ramp, from: 0, to: 1000000, period_s: 100000}
      - {slot: 2, card: CDI-13}
)";

class EncoderCard : public RackTest {
 protected:
  EncoderCard() : RackTest(mdp::parse_rack_config(kRack, "<encoder test>")) {
    to_op();
    drain_emergencies();
  }
  // One 1 ms cycle with the control words STW2_ENC / G1_STW1.
  void cycle(uint16_t stw2, uint16_t stw) {
    clock += 0.001;
    std::vector<uint8_t> out(device.output_bytes(), 0);
    le::put16(out.data(), stw2);
    le::put16(out.data() + 2, stw);
    device.write_outputs(out);
    in.assign(device.input_bytes(), 0);
    device.read_inputs(in);
  }
  // A master that counts its sign-of-life 1..15 and keeps control (STW2_ENC bit 10).
  void run(int cycles, uint16_t stw = 0) {
    for (int i = 0; i < cycles; ++i) {
      ls = ls >= 15 ? 1 : ls + 1;
      cycle(static_cast<uint16_t>(ls << 12 | 1u << 10), stw);
    }
  }
  uint16_t zsw2() const { return le::get16(in.data()); }
  uint16_t zsw() const { return le::get16(in.data() + 2); }
  uint32_t xist1() const { return le::get32(in.data() + 4); }
  uint32_t xist2() const { return le::get32(in.data() + 8); }
  int32_t nist_b() const { return static_cast<int32_t>(le::get32(in.data() + 12)); }
  coe::Object& settings() { return *device.dictionary().find(0x8000); }
  coe::Object& preset() { return *device.dictionary().find(0x8001); }
  EncoderDriver& encoder() { return *dynamic_cast<EncoderDriver*>(rack.driver(1)); }
  // An SDO download as the SDO server does it: check, commit, after_write.
  coe::AbortCode sdo(coe::Object& o, uint8_t sub, uint32_t value) {
    uint8_t b[4];
    le::put32(b, value);
    const std::span<const uint8_t> data(b, o.entry(sub)->byte_length());
    if (o.hooks().validate_write) {
      const auto rc = o.hooks().validate_write(o, sub, data, EsmState::PreOp);
      if (rc != coe::AbortCode::None) return rc;
    }
    o.set_u(sub, value);
    if (o.hooks().after_write) o.hooks().after_write(o, sub);
    return coe::AbortCode::None;
  }
  int ls = 0;
};

TEST_F(EncoderCard, TelegramLayoutAndPosition) {
  // RxPDO: STW2_ENC + G1_STW1 = 4 bytes; TxPDO: 2 + 2 + 4 + 4 + 4 = 16 bytes, then the DINx8.
  EXPECT_EQ(device.output_bytes(), 4);
  EXPECT_EQ(device.input_bytes(), 17);
  run(100);
  // t = 0.100 s at 10 rev/s: 1 rev = 65536 steps (default scaling 1:1), within a step of
  // floating-point rounding of the ramp.
  EXPECT_NEAR(static_cast<double>(xist2()), 65536.0, 1.0);
  EXPECT_EQ(xist1(), xist2());
  // ZSW2_ENC bit 9 "control requested", sign-of-life 1..15 in bits 12..15.
  EXPECT_EQ(zsw2() & 0x0FFF, 1u << 9);
  EXPECT_NE(zsw2() >> 12, 0);
  // NIST_B in steps/s: 655360 (the ramp's slope is exact; one step of quantisation per 1 ms
  // cycle is 1000 steps/s, the 7:3 filter averages it).
  EXPECT_NEAR(nist_b(), 655360, 1000);
}

TEST_F(EncoderCard, PresetOnTheControlBitEdgeWhileMoving) {
  ASSERT_EQ(sdo(settings(), enc::kPresetValue, 1000), coe::AbortCode::None);
  run(10);
  EXPECT_EQ(zsw() & (1u << 12), 0);
  run(1, 1u << 12);  // rising edge of bit 12: the position of this cycle becomes 1000
  EXPECT_EQ(xist2(), 1000u);
  EXPECT_NE(zsw() & (1u << 12), 0) << "acknowledged in G1_ZSW1 bit 12";
  run(1, 1u << 12);  // bit held: acknowledged, no second preset; the shaft moved 1 ms = 655.36
  EXPECT_NEAR(static_cast<double>(xist2()), 1655.0, 1.0);
  run(1);  // bit back to 0: acknowledgement cleared
  EXPECT_EQ(zsw() & (1u << 12), 0);
  const auto offset = static_cast<int32_t>(static_cast<uint32_t>(preset().get_u(enc::kOffset)));
  // The offset is readable and consistent: position = (unshifted + offset) mod 2^28.
  EXPECT_NE(offset, 0);
  // Shift by -1000 (bit 11 = 1): the position moves back by 1000 on the edge.
  ASSERT_EQ(sdo(settings(), enc::kPresetValue, static_cast<uint32_t>(-1000)), coe::AbortCode::None);
  run(1);
  const uint32_t before = xist2();
  run(1, 1u << 12 | 1u << 11);
  // One cycle of motion (655 or 656 steps) minus the 1000 shifted away.
  EXPECT_NEAR(static_cast<double>(xist2()), static_cast<double>(before) + 655.36 - 1000.0, 1.0);
}

TEST_F(EncoderCard, PresetBySdoAndNotWithoutClass4) {
  run(5);
  ASSERT_EQ(sdo(settings(), enc::kPresetValue, 7), coe::AbortCode::None);
  ASSERT_EQ(sdo(preset(), enc::kPresetCommand, enc::kPresetSet), coe::AbortCode::None);
  EXPECT_EQ(preset().get_u(enc::kPresetCommand), 0u) << "reads 0 once executed";
  EXPECT_EQ(encoder().position(), 7u);
  ASSERT_EQ(sdo(settings(), enc::kClass4, 0), coe::AbortCode::None);
  EXPECT_EQ(sdo(preset(), enc::kPresetCommand, enc::kPresetSet),
            coe::AbortCode::ParameterIncompatible);
}

TEST_F(EncoderCard, RefusedCombinationAbortsAndLeavesADiagnosisMessage) {
  drain_emergencies();
  // 65537 units per revolution on a 65536-step encoder: 0x06090031, nothing changes.
  EXPECT_EQ(sdo(settings(), enc::kUnitsPerRev, 65537), coe::AbortCode::ValueTooHigh);
  EXPECT_EQ(settings().get_u(enc::kUnitsPerRev), 65536u);
  EXPECT_TRUE(has_code(drain_emergencies(), 0x6320));
  // Units 1000 with the default range 2^28 > 1000 x 4096: a combination.
  EXPECT_EQ(sdo(settings(), enc::kUnitsPerRev, 1000), coe::AbortCode::ParameterIncompatible);
  // Range first, then units: accepted; 100 turns of 1000 units is a round axis.
  EXPECT_EQ(sdo(settings(), enc::kTotalRange, 100000), coe::AbortCode::None);
  EXPECT_EQ(sdo(settings(), enc::kUnitsPerRev, 1000), coe::AbortCode::None);
  run(1);
  EXPECT_EQ(device.dictionary().find(0x9000)->get_u(enc::kRoundAxis), 1u);
  EXPECT_EQ(sdo(settings(), enc::kCodeSequence, 2), coe::AbortCode::ValueTooHigh);
}

TEST_F(EncoderCard, MasterSignOfLifeFailure) {
  ASSERT_EQ(sdo(settings(), enc::kMaxLifeFailures, 3), coe::AbortCode::None);
  run(20);
  drain_emergencies();
  // The master's counter stops: +10 per cycle, failure at 10 x 3 = 30, i.e. the third cycle.
  const uint16_t stuck = static_cast<uint16_t>(ls << 12 | 1u << 10);
  cycle(stuck, 0);
  cycle(stuck, 0);
  EXPECT_EQ(zsw() & (1u << 15), 0);
  cycle(stuck, 0);
  EXPECT_NE(zsw() & (1u << 15), 0);
  EXPECT_EQ(xist2(), 0x0F04u);
  EXPECT_TRUE(has_code(drain_emergencies(), 0x8100));
  // Counting again does not clear it; the acknowledgement (bit 15 edge) does.
  run(5);
  EXPECT_NE(zsw() & (1u << 15), 0);
  run(1, 1u << 15);
  run(3);
  EXPECT_EQ(zsw() & (1u << 15), 0);
  EXPECT_NE(xist2(), 0x0F04u);
}

TEST_F(EncoderCard, InjectedFaultsSetTheErrorBitWithTheirCode) {
  struct Case {
    EncoderFault fault;
    uint16_t code;
    uint16_t emergency;
  };
  for (const Case c :
       {Case{EncoderFault::Hardware, 0x0001, 0x5000}, Case{EncoderFault::Jump, 0x1002, 0x7300},
        Case{EncoderFault::Frozen, 0x1003, 0x7300}}) {
    run(5);
    drain_emergencies();
    rack.set_encoder_fault(1, c.fault, true, 5000);
    run(1);
    EXPECT_NE(zsw() & (1u << 15), 0);
    EXPECT_EQ(xist2(), c.code);
    EXPECT_TRUE(has_code(drain_emergencies(), c.emergency));
    // Parking sensor (bit 14): no error shown.
    run(1, 1u << 14);
    EXPECT_EQ(zsw() & (1u << 15), 0);
    EXPECT_NE(zsw() & (1u << 14), 0);
    rack.set_encoder_fault(1, c.fault, false);
    EXPECT_TRUE(has_code(drain_emergencies(), 0x0000)) << "the removed message";
    run(1);
    EXPECT_NE(zsw() & (1u << 15), 0) << "latched until acknowledged";
    run(1, 1u << 15);
    run(1);
    EXPECT_EQ(zsw() & (1u << 15), 0);
  }
}

TEST_F(EncoderCard, FrozenPositionStaysAndJumpMovesIt) {
  run(10);
  rack.set_encoder_fault(1, EncoderFault::Frozen, true);
  run(1);
  const uint32_t frozen = encoder().position();
  run(10);
  EXPECT_EQ(encoder().position(), frozen);
  rack.set_encoder_fault(1, EncoderFault::Frozen, false);
  run(1);
  const uint32_t p = encoder().position();
  rack.set_encoder_fault(1, EncoderFault::Jump, true, 100000);
  run(1);
  EXPECT_NEAR(static_cast<double>(encoder().position()), p + 100000.0 + 655.36, 1.0);
}

TEST_F(EncoderCard, NothingAllocatesOnTheCyclicPath) {
  if (!rackcat::testing::CountAllocations::available()) GTEST_SKIP() << "sanitizer build";
  run(5);
  in.reserve(64);
  std::vector<uint8_t> out(device.output_bytes(), 0);
  rackcat::testing::CountAllocations count;
  // Sign-of-life, presets (set and shift), acknowledgement, a stopped sign-of-life and its
  // failure report, velocity: 3000 cycles.
  for (int i = 0; i < 3000; ++i) {
    clock += 0.001;
    if (i % 500 < 480) ls = ls >= 15 ? 1 : ls + 1;
    const uint16_t stw =
        static_cast<uint16_t>((i % 100 < 50 ? 1u << 12 : 0) | (i % 200 < 100 ? 1u << 11 : 0) |
                              (i % 500 == 499 ? 1u << 15 : 0));
    le::put16(out.data(), static_cast<uint16_t>(ls << 12 | 1u << 10));
    le::put16(out.data() + 2, stw);
    device.write_outputs(out);
    in.resize(device.input_bytes());
    device.read_inputs(in);
  }
  EXPECT_EQ(count.allocations(), 0u);
}

}  // namespace
}  // namespace rackcat::modules::testing
