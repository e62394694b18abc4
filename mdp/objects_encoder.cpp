// Objects of the absolute rotary encoder card (CAE-10, docs/ENCODER.md): settings 0x8nn0 (the
// encoder guide's acyclic parameters), preset 0x8nn1 and information 0x9nn0, per ETG.5001.1 §4
// in the module's configuration (0x8nnX) and information (0x9nnX) areas. Every write of 0x8nn0
// is checked as a whole against the guide's limits (mdp/encoder_settings.hpp); a refused write
// changes nothing and answers the abort code of the refusal.
#include "coe/bits.hpp"
#include "mdp/encoder_settings.hpp"
#include "mdp/object_dictionary_builder.hpp"
#include "mdp/od_helpers.hpp"

namespace rackcat::mdp {
namespace {

using namespace detail;
using coe::AbortCode;
namespace enc = encoder;

Object settings_object(const Module& m, const enc::Hardware& hw) {
  const enc::Settings d = enc::default_settings(hw);
  Object o(m.index(0x8000, 0), ObjectCode::Record, "ENC Settings", 0);
  const uint16_t rw = acc("rw");
  o.add(sub0(enc::kSettingsEntries));
  o.add(num(enc::kCodeSequence, "Code sequence", DataType::Unsigned8, rw, d.ccw));
  o.add(num(enc::kClass4, "Class 4 functionality", DataType::Unsigned8, rw, d.class4));
  o.add(num(enc::kPresetControl, "G1_XIST1 preset control", DataType::Unsigned8, rw,
            d.preset_not_xist1));
  o.add(num(enc::kScaling, "Scaling function control", DataType::Unsigned8, rw, d.scaling));
  o.add(num(enc::kUnitsPerRev, "Measuring units per revolution", DataType::Unsigned32, rw,
            d.units_per_rev));
  o.add(num(enc::kTotalRange, "Total measuring range", DataType::Unsigned32, rw, d.total_range));
  o.add(num(enc::kMaxLifeFailures, "Maximum master sign-of-life failures", DataType::Unsigned8, rw,
            d.max_life_failures));
  o.add(
      num(enc::kVelocityUnit, "Velocity measuring unit", DataType::Unsigned8, rw, d.velocity_unit));
  o.add(num(enc::kVelocityFilter, "Velocity filter", DataType::Unsigned8, rw, d.velocity_filter));
  o.add(num(enc::kPresetValue, "Preset value", DataType::Integer32, rw, 0));
  o.finalize();
  o.edit_hooks().validate_write = [hw](const Object& obj, int subindex,
                                       std::span<const uint8_t> data, EsmState) {
    // 0/1 switches (guide 3.11.1-3.11.4): any other value is out of the entry's range.
    for (uint8_t sub : {enc::kCodeSequence, enc::kClass4, enc::kPresetControl, enc::kScaling}) {
      const auto b = written_bytes(obj, sub, subindex, data);
      if (!b.empty() && b[0] > 1) return AbortCode::ValueTooHigh;
    }
    const enc::Settings s = enc::candidate_settings(obj, subindex, data);
    return enc::abort_code(enc::check(hw, s), s,
                           subindex > 0 ? static_cast<uint8_t>(subindex) : uint8_t{0});
  };
  return o;
}

Object preset_object(const Module& m) {
  Object o(m.index(0x8000, 1), ObjectCode::Record, "ENC Preset", 0);
  o.add(sub0(2));
  // Guide 3.11.8 "The offset value is calculated in the preset function": read only, stored
  // with the other parameters by 0xFBF2.
  o.add(num(enc::kOffset, "Offset value", DataType::Integer32, acc("ro"), 0));
  // Writing 1 sets the position to the preset value 0x8nn0:0A, 2 shifts it by that value
  // (G1_STW1 bit 11 "home position mode" 0/1); reads 0 once executed.
  o.add(ranged(enc::kPresetCommand, "Execute preset", DataType::Unsigned8, acc("rw"), 0, 0,
               enc::kPresetShift));
  o.finalize();
  return o;
}

Object info_object(const Module& m, const enc::Hardware& hw) {
  Object o(m.index(0x9000, 0), ObjectCode::Record, "ENC Information", 0);
  const uint16_t ro = acc("ro");
  o.add(sub0(enc::kLifeFailureCounter));
  o.add(
      num(enc::kStepsPerTurn, "Steps per revolution", DataType::Unsigned32, ro, hw.steps_per_turn));
  o.add(num(enc::kTurns, "Distinguishable revolutions", DataType::Unsigned32, ro, hw.turns));
  o.add(num(enc::kRoundAxis, "Round axis active", DataType::Unsigned8, ro, 0));
  o.add(num(enc::kProfileVersion, "Encoder profile version", DataType::Unsigned32, ro,
            enc::kProfileV41));
  o.add(num(enc::kErrorCode, "Sensor error code", DataType::Unsigned16, ro, 0));
  o.add(num(enc::kLifeFailureCounter, "Master sign-of-life failure counter", DataType::Unsigned16,
            ro, 0));
  o.finalize();
  return o;
}

}  // namespace

void add_encoder_objects(const RackConfig& cfg, coe::ObjectDictionary& od) {
  for (const auto& m : cfg.modules) {
    if (!m.card->encoder()) continue;
    const enc::Hardware hw = enc::hardware_of(cfg, m);
    od.add(settings_object(m, hw));
    od.add(preset_object(m));
  }
  for (const auto& m : cfg.modules) {
    if (m.card->encoder()) od.add(info_object(m, enc::hardware_of(cfg, m)));
  }
}

}  // namespace rackcat::mdp
