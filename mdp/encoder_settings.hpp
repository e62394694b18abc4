// Settings of the absolute rotary encoder card (CAE-10) after the encoder guide
// (the PROFINET absolute encoder user guide, "the guide"): the hardware
// (single-turn steps, distinguishable turns), the parameters of "Parameter for Acyclic Data
// Transmission" as CoE entries of 0x8nn0, and the rules the guide gives for their combination.
// The object layout and the mapping to the guide's parameters are in docs/ENCODER.md.
#pragma once

#include <cstdint>
#include <span>

#include "coe/abort_code.hpp"
#include "coe/object_dictionary.hpp"
#include "mdp/rack_config.hpp"

namespace rackcat::mdp::encoder {

// 0x8nn0 "ENC Settings" subindices (guide "Base Mode Parameter", "Device Parameter",
// "Vendor Parameter").
inline constexpr uint8_t kCodeSequence = 0x01;     // 0 CW increasing, 1 CCW increasing (3.11.1)
inline constexpr uint8_t kClass4 = 0x02;           // 1 = scaling/preset/code sequence act (3.11.2)
inline constexpr uint8_t kPresetControl = 0x03;    // 1 = preset does not affect G1_XIST1 (3.11.3)
inline constexpr uint8_t kScaling = 0x04;          // scaling function control (3.11.4)
inline constexpr uint8_t kUnitsPerRev = 0x05;      // measuring units per revolution (3.11.9)
inline constexpr uint8_t kTotalRange = 0x06;       // total measuring range (3.11.9)
inline constexpr uint8_t kMaxLifeFailures = 0x07;  // maximum master sign-of-life failures (3.11.10)
inline constexpr uint8_t kVelocityUnit = 0x08;    // 0 steps/s, 1 /100 ms, 2 /10 ms, 3 rpm (3.11.11)
inline constexpr uint8_t kVelocityFilter = 0x09;  // 0 fine, 1 normal, 2 coarse (3.11.12)
inline constexpr uint8_t kPresetValue = 0x0A;     // preset value, P65000 (3.11.7), INTEGER32
inline constexpr uint8_t kSettingsEntries = 0x0A;
// 0x8nn1 "ENC Preset": the offset the preset computed (3.11.8, stored by 0xFBF2) and a command
// entry that executes a preset by SDO (1 = set to the preset value, 2 = shift by it).
inline constexpr uint8_t kOffset = 0x01;
inline constexpr uint8_t kPresetCommand = 0x02;
inline constexpr uint8_t kPresetSet = 1;
inline constexpr uint8_t kPresetShift = 2;
// 0x9nn0 "ENC Information" (read only).
inline constexpr uint8_t kStepsPerTurn = 0x01;
inline constexpr uint8_t kTurns = 0x02;
inline constexpr uint8_t kRoundAxis = 0x03;       // 1 while the endless-shaft routine is active
inline constexpr uint8_t kProfileVersion = 0x04;  // 3.11.14: 0x0401 = V4.1
inline constexpr uint8_t kErrorCode = 0x05;       // the G1_XIST2 error code while a sensor error
inline constexpr uint8_t kLifeFailureCounter = 0x06;  // master sign-of-life failure counter

inline constexpr uint32_t kProfileV41 = 0x0401;

// Hardware: "maximum resolution of 65,536 steps per revolution (16 bits)", "up to 4096
// revolutions (12 bits)" (guide 1.1). Rack-file card options singleturn_bits (1..16, default
// 16) and multiturn_bits (0..12, default 12).
struct Hardware {
  uint32_t steps_per_turn = 1u << 16;
  uint32_t turns = 1u << 12;
  uint64_t total() const { return uint64_t{steps_per_turn} * turns; }
};
inline constexpr unsigned kMaxSingleturnBits = 16;
inline constexpr unsigned kMaxMultiturnBits = 12;

struct Settings {
  bool ccw = false;
  bool class4 = true;
  bool preset_not_xist1 = false;
  bool scaling = true;
  uint32_t units_per_rev = 1u << 16;
  uint32_t total_range = 1u << 28;
  uint8_t max_life_failures = 1;
  uint8_t velocity_unit = 0;
  uint8_t velocity_filter = 0;
  int32_t preset = 0;
};

// The card's hardware from its rack-file options; throws ConfigError (file:line) for a bad one.
Hardware hardware_of(const RackConfig& config, const Module& module);
// Default settings for the hardware: measuring units per revolution = steps per turn, total
// measuring range = the hardware's total resolution.
Settings default_settings(const Hardware& hw);
// Settings from an 0x8nn0 image: the object's own (empty `image`), or a complete-access
// candidate laid out the same way.
Settings read_settings(const coe::Object& settings_object, std::span<const uint8_t> image = {});
// The same with one entry replaced by the bytes of a single-entry write.
Settings candidate_settings(const coe::Object& settings_object, int subindex,
                            std::span<const uint8_t> data);

// Why a combination is refused, with the abort code it answers (guide "Scaling parameters",
// "Preset value": error 0x02 "Low or high limit exceeded" -> 0x06090031/32; a value that only
// the other parameters make impossible -> 0x06040043).
enum class Refusal : uint8_t {
  None,
  FlagNotBoolean,         // a 0/1 parameter written with another value
  UnitsPerRevZero,        // measuring units per revolution 0
  UnitsPerRevAboveSteps,  // more measuring units per revolution than the hardware has steps
  TotalRangeZero,         // total measuring range 0
  TotalRangeAboveTurns,   // total measuring range > units per revolution x turns
  LifeFailuresZero,       // maximum master sign-of-life failures outside 1..255
  VelocityUnit,           // velocity measuring unit not 0..3
  VelocityFilter,         // velocity filter not 0..2
  PresetOutOfRange,       // |preset| >= the position range
};
Refusal check(const Hardware& hw, const Settings& s);
// The abort code for a refusal, when `changed` is the subindex written (0 = complete access):
// the entry's own limits give 0x06090031/0x06090032, a combination 0x06040043.
coe::AbortCode abort_code(Refusal r, const Settings& s, uint8_t changed);
const char* refusal_text(Refusal r);

// The period of the position value: the total measuring range when class 4 and scaling are
// active, else the hardware's total resolution (guide 3.11.4: "If not, the physical position
// value is returned").
uint64_t position_range(const Hardware& hw, const Settings& s);
// Endless shaft (guide 3.11.13): needed when the hardware's turns hold no whole number of
// position periods, i.e. (turns x measuring units per revolution) / total range is not an
// integer; the encoder then keeps counting across the hardware's wrap by itself.
bool round_axis(const Hardware& hw, const Settings& s);

}  // namespace rackcat::mdp::encoder
