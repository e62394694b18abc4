// The EtherCAT state machine's states (ETG.1000.6 §5.3), encoded as in AL control 0x0120 and
// AL status 0x0130 bits 3..0 (ETG.1000.6 Table 9, ETG.1000.4 §6.4). The one state type of the
// stack: the firmware's ESM reports it, CoE access rights (ETG.1000.6 §5.6.2) are checked
// against it.
#pragma once

#include <cstdint>

namespace rackcat {

enum class EsmState : uint8_t { Init = 0x01, PreOp = 0x02, Boot = 0x03, SafeOp = 0x04, Op = 0x08 };

// Whether `v` (AL control bits 3..0) names a state; anything else is refused with AL status
// 0x0012 "unknown requested state" (ETG.1000.6 Table 11).
constexpr bool is_esm_state(uint8_t v) {
  return v == 0x01 || v == 0x02 || v == 0x03 || v == 0x04 || v == 0x08;
}

// The state's name as masters and logs print it; "?" for a value that names no state.
constexpr const char* esm_state_name(uint8_t v) {
  switch (v & 0x0F) {
    case 0x01:
      return "INIT";
    case 0x02:
      return "PREOP";
    case 0x03:
      return "BOOT";
    case 0x04:
      return "SAFEOP";
    case 0x08:
      return "OP";
    default:
      return "?";
  }
}
constexpr const char* esm_state_name(EsmState s) {
  return esm_state_name(static_cast<uint8_t>(s));
}

}  // namespace rackcat
