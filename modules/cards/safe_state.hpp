// Output substitute values on leaving OP (guide §2.5, Tables 7-10: 0x4nn0..0x4nn3).
//
// Per channel n: Enable bit n (subindex 1) and Action bit n (subindex 2).
//   enable = 1, action = 1: the output takes the configured Value (bit n of subindex 3 for
//                           digital cards, subindex 3 + n for analog cards);
//   enable = 1, action = 0: the output holds its current value;
//   enable = 0:             no configured action: the output is de-energised (0 / 0 V), the
//                           default EtherCAT behaviour for outputs outside OP.
// The same rule applies on every transition out of OP (master request, SM watchdog, RIM loss
// with Detect Modules Override 0).
#pragma once

#include <cstdint>

namespace rackcat::modules {

enum class SafeAction : uint8_t { DeEnergise, Hold, SetValue };

constexpr SafeAction safe_action(uint32_t enable, uint32_t action, unsigned channel) {
  const bool en = (enable >> channel) & 1u;
  const bool act = (action >> channel) & 1u;
  if (!en) return SafeAction::DeEnergise;
  return act ? SafeAction::SetValue : SafeAction::Hold;
}

// Digital outputs: the new output word for `channels` channels.
constexpr uint32_t digital_safe_state(uint32_t current, uint32_t enable, uint32_t action,
                                      uint32_t value, unsigned channels) {
  uint32_t out = 0;
  for (unsigned n = 0; n < channels; ++n) {
    uint32_t bit = 0;
    switch (safe_action(enable, action, n)) {
      case SafeAction::DeEnergise:
        bit = 0;
        break;
      case SafeAction::Hold:
        bit = (current >> n) & 1u;
        break;
      case SafeAction::SetValue:
        bit = (value >> n) & 1u;
        break;
    }
    out |= bit << n;
  }
  return out;
}

// Analog outputs: the new code of one channel.
constexpr uint16_t analog_safe_state(uint16_t current, uint32_t enable, uint32_t action,
                                     uint16_t value, unsigned channel) {
  switch (safe_action(enable, action, channel)) {
    case SafeAction::DeEnergise:
      return 0;  // 0 V (two's complement code 0)
    case SafeAction::Hold:
      return current;
    case SafeAction::SetValue:
      return value;
  }
  return 0;
}

}  // namespace rackcat::modules
