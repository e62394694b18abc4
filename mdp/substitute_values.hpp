// Substitute values, after the INTERBUS Basic profile (INTERBUS Basic Profile 1.0
// §7.3.2 "Substitute value behavior", objects 0x0020
// PDTimeoutCode / 0x0024 ResetCode for outputs, 0x0030 PF_Code and 0x0031 PDIN_Subst for inputs)
// in the device's manufacturer range next to the guide's safe states 0x4nn0..0x4nn3 (§2.5):
//
//   0x4nn8 Output Substitute Reaction  ARRAY [channels] OF UINT16, rw   (output modules)
//   0x4nnA Input Substitute Reaction   ARRAY [channels] OF UINT16, rw   (input modules)
//   0x4nnB Input Substitute Value      ARRAY [channels] OF UINT16, rw   (the channel's PD code)
//   0x4nnC Input Substitute Status     UINT16, ro, TxPDO-mappable: bit n = channel n reports
//                                      a substitute (its source is missing)
//
// An output reaction applies whenever the outputs lose valid data: leaving OP (master request,
// SM watchdog, RIM loss with Detect Modules Override 0). The reaction codes are the profile's;
// 0x8000 (manufacturer-specific range) is the guide's own rule, 0x4nnX enable/action/value,
// so a rack that never writes 0x4nn8 behaves exactly as the guide says. A RIM that goes offline
// drives its own outputs de-energised whatever is configured (guide Table 23, TÜV-safe level).
// An input reaction applies while a channel's source is missing: its RIM is not online, or the
// sensor is open (thermocouple/RTD break). 0x8000 is again the guide's behaviour (0 while the
// RIM is offline, 0x7FFF on a sensor break).
// All four objects except the status are stored by 0xFBF2 (mdp/parameter_set.cpp).
#pragma once

#include <cstdint>

#include "mdp/card_catalogue.hpp"

namespace rackcat::mdp::substitute {

inline constexpr uint8_t kOutputReaction = 0x8;  // nibble of 0x4nnX
inline constexpr uint8_t kInputReaction = 0xA;
inline constexpr uint8_t kInputValue = 0xB;
inline constexpr uint8_t kInputStatus = 0xC;

// INTERBUS PDTimeoutCode / PF_Code values.
inline constexpr uint16_t kZeros = 0x0000;       // "0" to all bits
inline constexpr uint16_t kOnes = 0x0001;        // "1" to all bits (outputs only)
inline constexpr uint16_t kHoldLast = 0x0002;    // the last valid value
inline constexpr uint16_t kSubstitute = 0x0003;  // outputs: 0x4nnX Value; inputs: 0x4nnB
inline constexpr uint16_t kMinimum = 0x0004;     // lowest permissible value (outputs only)
inline constexpr uint16_t kMaximum = 0x0005;     // highest permissible value (outputs only)
inline constexpr uint16_t kGuide = 0x8000;       // manufacturer-specific: the guide's rule

constexpr bool valid_output_reaction(uint64_t code) {
  return code <= kMaximum || code == kGuide;
}
constexpr bool valid_input_reaction(uint64_t code) {
  return code == kZeros || code == kHoldLast || code == kSubstitute || code == kGuide;
}

constexpr bool has_output_channels(const CardType& c) {
  switch (c.signal) {
    case Signal::DigitalOutSource:
    case Signal::DigitalOutSink:
    case Signal::DigitalOutOpto:
    case Signal::Relay:
    case Signal::RelayForceGuided:
    case Signal::DigitalInOut:
    case Signal::AnalogOut:
      return true;
    default:
      return false;
  }
}

constexpr bool has_input_channels(const CardType& c) {
  switch (c.signal) {
    case Signal::DigitalIn:
    case Signal::DigitalInInverted:
    case Signal::DigitalInOut:
    case Signal::AnalogIn:
    case Signal::Thermocouple:
    case Signal::Rtd:
      return true;
    default:
      return false;
  }
}

}  // namespace rackcat::mdp::substitute
