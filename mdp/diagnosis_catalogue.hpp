// The device's diagnosis messages (ETG.1020 ch. 13): every text ID the rack puts into the
// history 0x10F3, its type, the CoE Emergency error code that goes out with it, and its text
// with parameters (%1 RIM, %2 module, %3 channel, %4 detail), as the ESI DiagMessages carry it
// (ETG.2000 DiagnosticsType) and `rackcat ctl diag` prints it.
//
// Text IDs: bits 15..12 the class (0x1 information, 0x4 warning, 0x8 error), bits 11..8 the
// area (1 control module, 2 RIM, 6 I/O channel, 7 UART channel, 8 encoder), bits 7..0 the cause;
// for I/O channels the cause is the PROFINET/PROFIBUS ChannelErrorType of the diagnostic records
// (0x0001 short circuit, 0x0004 overload, 0x0005 overtemperature, 0x0006 line break, 0x0007
// upper limit exceeded, 0x0008 lower limit undershot). The message saying a cause has gone
// ("disappears", the INTERBUS Basic profile's priorities 0x81/0x82 "removed") has the same
// area and cause with class 0x1: removed_text(appears).
//
// Parameters of every message, in this order (ETG.1020 parameter flag = data type index):
//   UNSIGNED8 RIM (0 = control module), UNSIGNED16 module number (0 = none),
//   UNSIGNED8 channel (0-based, 0xFF = none), UNSIGNED16 detail (cause-specific, 0 = none).
// The Emergency's 5 manufacturer bytes stay as before: [0] RIM, [1] module, [2] event bit
// (0xFF = none), [3..4] channel mask.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "coe/diagnosis_history.hpp"

namespace rackcat::mdp::diag {

struct DiagText {
  uint16_t text_id;
  uint16_t emergency_code;  // CoE Emergency error code sent with the message (0 = removed)
  uint8_t error_register;   // 0x1001-style bits sent with the Emergency
  std::string_view text;    // %1 RIM, %2 module, %3 channel, %4 detail
};

constexpr coe::diag::Type type_of(uint16_t text_id) {
  switch (text_id >> 12) {
    case 0x8:
      return coe::diag::Type::Error;
    case 0x4:
      return coe::diag::Type::Warning;
    default:
      return coe::diag::Type::Info;
  }
}
constexpr uint16_t removed_text(uint16_t appears) {
  return static_cast<uint16_t>((appears & 0x0FFF) | 0x1000);
}

// PROFINET ChannelErrorType (diagnostic records, "Channel Error Type").
enum class ChannelError : uint8_t {
  ShortCircuit = 0x01,
  Overload = 0x04,
  Overtemperature = 0x05,
  LineBreak = 0x06,
  UpperLimit = 0x07,
  LowerLimit = 0x08,
};

// Text IDs.
namespace text {
inline constexpr uint16_t kEmergency = 0x8100;  // an Emergency without its own text
inline constexpr uint16_t kCpuOverTemperature = 0x8101;
inline constexpr uint16_t kCpuFanWarning = 0x4102;
inline constexpr uint16_t kCpuFanError = 0x8103;
inline constexpr uint16_t kCpuFanFailure = 0x8104;
inline constexpr uint16_t kWatchdog = 0x8105;
inline constexpr uint16_t kRimNotOnline = 0x4201;
inline constexpr uint16_t kRimOffline = 0x8202;
inline constexpr uint16_t kRimCommError = 0x8203;
inline constexpr uint16_t kSlotFanWarning = 0x4211;
inline constexpr uint16_t kSlotFanError = 0x8212;
inline constexpr uint16_t kSlotFanFailure = 0x8213;
inline constexpr uint16_t kPsFanWarning = 0x4214;
inline constexpr uint16_t kPsFanError = 0x8215;
inline constexpr uint16_t kPsFanFailure = 0x8216;
inline constexpr uint16_t kSlotMachineMcm0 = 0x8221;
inline constexpr uint16_t kSoutCompareMcm0 = 0x8222;
inline constexpr uint16_t kSlotMachineMcm1 = 0x8223;
inline constexpr uint16_t kSoutCompareMcm1 = 0x8224;
inline constexpr uint16_t kSafeWiring = 0x4601;    // short circuit to 0 V: output reads low
inline constexpr uint16_t kUnsafeWiring = 0x8601;  // short circuit to supply: reads high
inline constexpr uint16_t kOverload = 0x8604;
inline constexpr uint16_t kOvertemperature = 0x8605;
inline constexpr uint16_t kLineBreak = 0x8606;
inline constexpr uint16_t kUpperLimit = 0x4607;
inline constexpr uint16_t kLowerLimit = 0x4608;
inline constexpr uint16_t kUartOverflow = 0x4701;
inline constexpr uint16_t kUartFraming = 0x4702;
inline constexpr uint16_t kUartParity = 0x4703;
inline constexpr uint16_t kUartTxOverflow = 0x4704;
// Area 8: absolute encoder cards (docs/ENCODER.md); detail = the G1_XIST2 error code, or for a
// refused parameter the subindex of 0x8nn0 (0 = complete access).
inline constexpr uint16_t kEncoderParameter = 0x4805;
inline constexpr uint16_t kEncoderHardware = 0x8801;
inline constexpr uint16_t kEncoderJump = 0x8802;
inline constexpr uint16_t kEncoderFrozen = 0x8803;
inline constexpr uint16_t kEncoderLifeSign = 0x8804;
}  // namespace text

// Text ID of a channel error (area 6, class by severity).
uint16_t channel_error_text(ChannelError e);

// Every message of the device, appears and removed texts alike, in text ID order.
std::span<const DiagText> catalogue();
const DiagText* find(uint16_t text_id);

// The text ID for an Emergency raised by the rack (modules/rack/events.hpp codes and data bytes):
// the exception tree's causes by event bit, channel faults by code, removals by what they name.
uint16_t text_for_emergency(uint16_t code, std::span<const uint8_t, 5> data);

// The message's text with its parameters filled in (%1..%4), for `rackcat ctl diag`.
std::string format(const DiagText& t, uint8_t rim, uint16_t module, uint8_t channel,
                   uint16_t detail);

}  // namespace rackcat::mdp::diag
