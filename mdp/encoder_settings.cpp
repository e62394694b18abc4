// Encoder settings and their combination rules: see encoder_settings.hpp and docs/ENCODER.md.
#include "mdp/encoder_settings.hpp"

#include <cstdlib>
#include <string>

#include "coe/bits.hpp"

namespace rackcat::mdp::encoder {
namespace {

unsigned option_bits(const RackConfig& config, const SlotCard& sc, const char* key, unsigned def,
                     unsigned lo, unsigned hi) {
  const auto it = sc.options.find(key);
  if (it == sc.options.end()) return def;
  char* end = nullptr;
  const long v = std::strtol(it->second.c_str(), &end, 10);
  if (end == it->second.c_str() || *end != '\0' || v < static_cast<long>(lo) ||
      v > static_cast<long>(hi)) {
    throw ConfigError(config.source, sc.line,
                      "slot " + std::to_string(sc.slot) + ": " + key + " must be an integer " +
                          std::to_string(lo) + ".." + std::to_string(hi) + ", not '" + it->second +
                          "'");
  }
  return static_cast<unsigned>(v);
}

uint64_t value_of(const coe::Object& o, std::span<const uint8_t> image, uint8_t sub) {
  if (image.empty()) return o.get_u(sub);
  const coe::Entry* e = o.entry(sub);
  if (!e) return 0;
  const size_t at = e->bit_offset / 8;
  if (at + e->byte_length() > image.size()) return o.get_u(sub);
  return le::get(image.data() + at, e->byte_length());
}

}  // namespace

Hardware hardware_of(const RackConfig& config, const Module& module) {
  const SlotCard& sc = config.slot_card(module);
  Hardware hw;
  hw.steps_per_turn =
      1u << option_bits(config, sc, "singleturn_bits", kMaxSingleturnBits, 1, kMaxSingleturnBits);
  hw.turns =
      1u << option_bits(config, sc, "multiturn_bits", kMaxMultiturnBits, 0, kMaxMultiturnBits);
  return hw;
}

Settings default_settings(const Hardware& hw) {
  Settings s;
  s.units_per_rev = hw.steps_per_turn;
  s.total_range = static_cast<uint32_t>(hw.total());
  return s;
}

Settings read_settings(const coe::Object& o, std::span<const uint8_t> image) {
  // A flag holds whatever was written (check() refuses values other than 0/1 before they are
  // committed); any non-zero value reads as set.
  Settings s;
  s.ccw = value_of(o, image, kCodeSequence) != 0;
  s.class4 = value_of(o, image, kClass4) != 0;
  s.preset_not_xist1 = value_of(o, image, kPresetControl) != 0;
  s.scaling = value_of(o, image, kScaling) != 0;
  s.units_per_rev = static_cast<uint32_t>(value_of(o, image, kUnitsPerRev));
  s.total_range = static_cast<uint32_t>(value_of(o, image, kTotalRange));
  s.max_life_failures = static_cast<uint8_t>(value_of(o, image, kMaxLifeFailures));
  s.velocity_unit = static_cast<uint8_t>(value_of(o, image, kVelocityUnit));
  s.velocity_filter = static_cast<uint8_t>(value_of(o, image, kVelocityFilter));
  s.preset = static_cast<int32_t>(static_cast<uint32_t>(value_of(o, image, kPresetValue)));
  return s;
}

Settings candidate_settings(const coe::Object& o, int subindex, std::span<const uint8_t> data) {
  if (subindex == -1) return read_settings(o, data);
  Settings s = read_settings(o);
  if (subindex < 1 || data.empty()) return s;
  const uint64_t v = le::get(data.data(), std::min<size_t>(data.size(), 8));
  switch (subindex) {
    case kCodeSequence:
    case kClass4:
    case kPresetControl:
    case kScaling:
      // Keep a non-boolean visible to check(): flag_raw below.
      break;
    case kUnitsPerRev:
      s.units_per_rev = static_cast<uint32_t>(v);
      break;
    case kTotalRange:
      s.total_range = static_cast<uint32_t>(v);
      break;
    case kMaxLifeFailures:
      s.max_life_failures = static_cast<uint8_t>(v);
      break;
    case kVelocityUnit:
      s.velocity_unit = static_cast<uint8_t>(v);
      break;
    case kVelocityFilter:
      s.velocity_filter = static_cast<uint8_t>(v);
      break;
    case kPresetValue:
      s.preset = static_cast<int32_t>(static_cast<uint32_t>(v));
      break;
    default:
      break;
  }
  if (subindex == kCodeSequence) s.ccw = v != 0;
  if (subindex == kClass4) s.class4 = v != 0;
  if (subindex == kPresetControl) s.preset_not_xist1 = v != 0;
  if (subindex == kScaling) s.scaling = v != 0;
  return s;
}

uint64_t position_range(const Hardware& hw, const Settings& s) {
  return s.class4 && s.scaling ? uint64_t{s.total_range} : hw.total();
}

bool round_axis(const Hardware& hw, const Settings& s) {
  const uint64_t range = position_range(hw, s);
  if (range == 0) return false;
  // Guide 3.11.13: (4096 x measuring units per revolution) / total resolution = integer, with
  // 4096 the hardware's turns. Unscaled, the period is the hardware's own and always fits.
  if (!(s.class4 && s.scaling)) return false;
  return (uint64_t{hw.turns} * s.units_per_rev) % range != 0;
}

Refusal check(const Hardware& hw, const Settings& s) {
  if (s.units_per_rev == 0) return Refusal::UnitsPerRevZero;
  if (s.units_per_rev > hw.steps_per_turn) return Refusal::UnitsPerRevAboveSteps;
  if (s.total_range == 0) return Refusal::TotalRangeZero;
  if (uint64_t{s.total_range} > uint64_t{s.units_per_rev} * hw.turns) {
    return Refusal::TotalRangeAboveTurns;
  }
  if (s.max_life_failures == 0) return Refusal::LifeFailuresZero;
  if (s.velocity_unit > 3) return Refusal::VelocityUnit;
  if (s.velocity_filter > 2) return Refusal::VelocityFilter;
  const auto range = static_cast<int64_t>(position_range(hw, s));
  if (s.preset >= range || s.preset <= -range) return Refusal::PresetOutOfRange;
  return Refusal::None;
}

coe::AbortCode abort_code(Refusal r, const Settings& s, uint8_t changed) {
  using coe::AbortCode;
  switch (r) {
    case Refusal::None:
      return AbortCode::None;
    case Refusal::FlagNotBoolean:
    case Refusal::VelocityUnit:
    case Refusal::VelocityFilter:
      return AbortCode::ValueTooHigh;
    case Refusal::UnitsPerRevZero:
    case Refusal::TotalRangeZero:
    case Refusal::LifeFailuresZero:
      return AbortCode::ValueTooLow;
    case Refusal::UnitsPerRevAboveSteps:
      // The hardware's steps are the entry's own upper limit.
      return AbortCode::ValueTooHigh;
    case Refusal::TotalRangeAboveTurns:
      return changed == kTotalRange ? AbortCode::ValueTooHigh : AbortCode::ParameterIncompatible;
    case Refusal::PresetOutOfRange:
      if (changed != kPresetValue) return AbortCode::ParameterIncompatible;
      return s.preset < 0 ? AbortCode::ValueTooLow : AbortCode::ValueTooHigh;
  }
  return AbortCode::GeneralError;
}

const char* refusal_text(Refusal r) {
  switch (r) {
    case Refusal::None:
      return "accepted";
    case Refusal::FlagNotBoolean:
      return "a switch parameter takes 0 or 1";
    case Refusal::UnitsPerRevZero:
      return "measuring units per revolution 0";
    case Refusal::UnitsPerRevAboveSteps:
      return "more measuring units per revolution than steps per revolution";
    case Refusal::TotalRangeZero:
      return "total measuring range 0";
    case Refusal::TotalRangeAboveTurns:
      return "total measuring range above units per revolution x turns";
    case Refusal::LifeFailuresZero:
      return "maximum master sign-of-life failures 0 (1..255)";
    case Refusal::VelocityUnit:
      return "velocity measuring unit not 0..3";
    case Refusal::VelocityFilter:
      return "velocity filter not 0..2";
    case Refusal::PresetOutOfRange:
      return "preset value outside the position range";
  }
  return "refused";
}

}  // namespace rackcat::mdp::encoder
