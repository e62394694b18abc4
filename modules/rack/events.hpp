// Event bits of the control module and the RIMs (guide §3.2 Table 15, §3.3 Table 16) and the
// CoE Emergency codes rackcat raises when the exception tree changes (docs/MODULES.md).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>

namespace rackcat::modules {

// RIM communication state, 0x2rr1:08 bits 1..0 (guide Table 16).
enum class RimState : uint8_t { Offline = 0, Connected = 1, Online = 2, Error = 3 };

// The one name table of the RIM states, indexed by the 0x2rr1:08 value: what the control API
// answers and accepts and what `rackcat rim --watch` prints.
inline constexpr std::array<std::string_view, 4> kRimStateNames{"offline", "connected", "online",
                                                                "error"};
constexpr std::string_view rim_state_name(RimState s) {
  return kRimStateNames[static_cast<uint8_t>(s) & 0x3];
}
constexpr std::optional<RimState> rim_state_from_name(std::string_view name) {
  for (size_t i = 0; i < kRimStateNames.size(); ++i) {
    if (kRimStateNames[i] == name) return static_cast<RimState>(i);
  }
  return std::nullopt;
}

namespace rim_event {
inline constexpr uint32_t kStateBits = 0x3;            // bits 1..0, active, not latched
inline constexpr uint32_t kStateWarning = 1u << 2;     // ONLINE -> CONNECTED (not online)
inline constexpr uint32_t kStateError = 1u << 3;       // ONLINE -> OFFLINE
inline constexpr uint32_t kCommError = 1u << 4;        // offline through a comm. error
inline constexpr uint32_t kSlotFanWarning = 1u << 8;   // deviation below -15 %
inline constexpr uint32_t kSlotFanError = 1u << 9;     // below -30 %
inline constexpr uint32_t kSlotFanFailure = 1u << 10;  // below -50 %
inline constexpr uint32_t kPsFanWarning = 1u << 12;
inline constexpr uint32_t kPsFanError = 1u << 13;
inline constexpr uint32_t kPsFanFailure = 1u << 14;
inline constexpr uint32_t kSlotMachineMcm0 = 1u << 16;
inline constexpr uint32_t kSoutCompareMcm0 = 1u << 17;
inline constexpr uint32_t kSlotMachineMcm1 = 1u << 18;
inline constexpr uint32_t kSoutCompareMcm1 = 1u << 19;
// Table 16 sorts the flags into warnings and errors (global details 0xF3x6 / 0xF3x8).
inline constexpr uint32_t kWarnings = kStateWarning | kSlotFanWarning | kPsFanWarning;
inline constexpr uint32_t kErrors = kStateError | kCommError | kSlotFanError | kSlotFanFailure |
                                    kPsFanError | kPsFanFailure | kSlotMachineMcm0 |
                                    kSoutCompareMcm0 | kSlotMachineMcm1 | kSoutCompareMcm1;
}  // namespace rim_event

namespace device_event {  // 0x2000:0A, guide Table 15
inline constexpr uint32_t kCpuFanWarning = 1u << 8;
inline constexpr uint32_t kCpuFanError = 1u << 9;
inline constexpr uint32_t kCpuFanFailure = 1u << 10;
inline constexpr uint32_t kWarnings = kCpuFanWarning;
inline constexpr uint32_t kErrors = kCpuFanError | kCpuFanFailure;
}  // namespace device_event

// Fan thresholds (guide §3.2/§3.3, "RPM dropped below 15/30/50 % of nominal" read as the
// deviation from nominal 0x2000:0D / 0x2rr1:0A-0B reaching -15/-30/-50 %, the only reading
// in which warning < error < failure). Returns bits in the order warning, error, failure
// starting at bit 0.
constexpr uint32_t fan_level_bits(double deviation_percent) {
  uint32_t bits = 0;
  if (deviation_percent <= -15.0) bits |= 1u;
  if (deviation_percent <= -30.0) bits |= 2u;
  if (deviation_percent <= -50.0) bits |= 4u;
  return bits;
}

// CoE Emergency error codes (CiA 301 style, ETG.1000.6 §5.6.4).
namespace emcy {
inline constexpr uint16_t kNoError = 0x0000;          // a cause went away
inline constexpr uint16_t kUnsafeWiring = 0x2320;     // output driven low, wire reads high
inline constexpr uint16_t kSafeWiring = 0x2330;       // output driven high, wire reads low
inline constexpr uint16_t kOverTemperature = 0x4210;  // CPU zone above the limit
inline constexpr uint16_t kFan = 0x5000;              // device hardware: a fan below nominal
inline constexpr uint16_t kSafetyMcu = 0x6000;        // SLOT machine / SOUT compare (MCM)
inline constexpr uint16_t kRimComm = 0x7500;          // RIM communication error
inline constexpr uint16_t kPdTimeout = 0x8110;        // SM watchdog: process-data timeout
inline constexpr uint16_t kModuleMissing = 0xA001;    // RIM not online: its modules are gone
// 0x1001-style error register bits.
inline constexpr uint8_t kRegGeneric = 0x01;
inline constexpr uint8_t kRegCurrent = 0x02;
inline constexpr uint8_t kRegTemperature = 0x08;
inline constexpr uint8_t kRegCommunication = 0x10;
inline constexpr uint8_t kRegManufacturer = 0x80;
}  // namespace emcy

// AL status code when a RIM with mapped process data is lost in OP with Detect Modules
// Override 0 (guide Table 23): 0x0070 "detected module ident list does not match" (ETG.1000.6
// Table 11 / ETG.5001.1) — the modules the master configured are no longer there.
inline constexpr uint16_t kAlStatusModuleMissing = 0x0070;

}  // namespace rackcat::modules
