// Substitute value rules of one channel (mdp/substitute_values.hpp; INTERBUS Basic profile
// §7.3.2, PDTimeoutCode 0x0020 / PF_Code 0x0030). Pure functions of codes, no allocation.
#pragma once

#include <cstdint>

#include "mdp/substitute_values.hpp"

namespace rackcat::modules {

// The codes a card gives its extremes: "1" to all bits, lowest and highest permissible value.
struct ChannelCodes {
  uint32_t ones = 1;
  uint32_t lowest = 0;
  uint32_t highest = 1;
};

// An output channel losing valid data. `guide` is the code the guide's 0x4nnX enable/action
// rule gives (safe_state.hpp), `current` the code driven now (the last valid one), `value` the
// channel's 0x4nnX Value.
constexpr uint32_t output_substitute(uint16_t reaction, uint32_t guide, uint32_t current,
                                     uint32_t value, ChannelCodes k) {
  namespace s = mdp::substitute;
  switch (reaction) {
    case s::kZeros:
      return 0;
    case s::kOnes:
      return k.ones;
    case s::kHoldLast:
      return current;
    case s::kSubstitute:
      return value;
    case s::kMinimum:
      return k.lowest;
    case s::kMaximum:
      return k.highest;
    default:
      return guide;
  }
}

// An input channel whose source is missing. `guide` is what the card reports by itself (0 with
// its RIM offline, 0x7FFF on a sensor break), `last_valid` the last code from a present source,
// `value` the channel's 0x4nnB.
constexpr uint32_t input_substitute(uint16_t reaction, uint32_t guide, uint32_t last_valid,
                                    uint32_t value) {
  namespace s = mdp::substitute;
  switch (reaction) {
    case s::kZeros:
      return 0;
    case s::kHoldLast:
      return last_valid;
    case s::kSubstitute:
      return value;
    default:
      return guide;
  }
}

}  // namespace rackcat::modules
