// The device's diagnosis texts (ETG.1020 ch. 13, ESI DiagMessages): see diagnosis_catalogue.hpp.
#include "mdp/diagnosis_catalogue.hpp"

#include <algorithm>
#include <array>
#include <cstdio>

namespace rackcat::mdp::diag {
namespace {

// CoE Emergency codes (CiA 301 classes; 0xFFxx device specific, ETG.1000.6 §5.6.4).
constexpr uint8_t kGen = 0x01, kCur = 0x02, kTemp = 0x08, kComm = 0x10, kMfg = 0x80;

constexpr std::array kTexts = {
    DiagText{0x1101, 0x0000, 0, "CPU zone temperature back below the limit"},
    DiagText{0x1102, 0x0000, 0, "CPU fan speed back above the warning level"},
    DiagText{0x1103, 0x0000, 0, "CPU fan error removed"},
    DiagText{0x1104, 0x0000, 0, "CPU fan failure removed"},
    DiagText{0x1201, 0x0000, 0, "RIM %1 online again"},
    DiagText{0x1202, 0x0000, 0, "RIM %1 no longer offline"},
    DiagText{0x1203, 0x0000, 0, "RIM %1 communication error removed"},
    DiagText{0x1211, 0x0000, 0, "RIM %1 slot-card fan speed back above the warning level"},
    DiagText{0x1212, 0x0000, 0, "RIM %1 slot-card fan error removed"},
    DiagText{0x1213, 0x0000, 0, "RIM %1 slot-card fan failure removed"},
    DiagText{0x1214, 0x0000, 0, "RIM %1 power-supply fan speed back above the warning level"},
    DiagText{0x1215, 0x0000, 0, "RIM %1 power-supply fan error removed"},
    DiagText{0x1216, 0x0000, 0, "RIM %1 power-supply fan failure removed"},
    DiagText{0x1221, 0x0000, 0, "RIM %1 MCM 0 SLOT machine error removed"},
    DiagText{0x1222, 0x0000, 0, "RIM %1 MCM 0 SOUT compare error removed"},
    DiagText{0x1223, 0x0000, 0, "RIM %1 MCM 1 SLOT machine error removed"},
    DiagText{0x1224, 0x0000, 0, "RIM %1 MCM 1 SOUT compare error removed"},
    DiagText{0x1601, 0x0000, 0, "Module %2 channel %3: short circuit removed"},
    DiagText{0x1604, 0x0000, 0, "Module %2 channel %3: overload removed"},
    DiagText{0x1605, 0x0000, 0, "Module %2 channel %3: overtemperature removed"},
    DiagText{0x1606, 0x0000, 0, "Module %2 channel %3: line break removed"},
    DiagText{0x1607, 0x0000, 0, "Module %2 channel %3: back below the upper limit"},
    DiagText{0x1608, 0x0000, 0, "Module %2 channel %3: back above the lower limit"},
    DiagText{0x1801, 0x0000, 0, "Module %2: encoder hardware error removed"},
    DiagText{0x1802, 0x0000, 0, "Module %2: encoder position jump removed"},
    DiagText{0x1803, 0x0000, 0, "Module %2: encoder position no longer frozen"},
    DiagText{0x1804, 0x0000, 0, "Module %2: master sign-of-life failure removed"},
    DiagText{text::kCpuFanWarning, 0x5000, kGen | kTemp, "CPU fan speed 15 % below nominal"},
    DiagText{text::kRimNotOnline, 0xA001, kGen | kComm,
             "RIM %1 connected but not online: its modules are missing"},
    DiagText{text::kSlotFanWarning, 0x5000, kGen | kTemp,
             "RIM %1 slot-card fan speed 15 % below nominal"},
    DiagText{text::kPsFanWarning, 0x5000, kGen | kTemp,
             "RIM %1 power-supply fan speed 15 % below nominal"},
    DiagText{text::kSafeWiring, 0x2330, kGen | kCur | kMfg,
             "Module %2 channel %3: short circuit to 0 V (safe wiring fault)"},
    DiagText{text::kUpperLimit, 0xFF07, kGen | kMfg,
             "Module %2 channel %3: upper limit exceeded (overrange)"},
    DiagText{text::kLowerLimit, 0xFF08, kGen | kMfg,
             "Module %2 channel %3: lower limit undershot (underrange)"},
    DiagText{text::kUartOverflow, 0xFF71, kGen | kComm,
             "Module %2 UART channel %3: receive buffer overflow"},
    DiagText{text::kUartFraming, 0xFF72, kGen | kComm, "Module %2 UART channel %3: framing error"},
    DiagText{text::kUartParity, 0xFF73, kGen | kComm, "Module %2 UART channel %3: parity error"},
    DiagText{text::kUartTxOverflow, 0xFF74, kGen | kComm,
             "Module %2 UART channel %3: transmit buffer overflow"},
    DiagText{text::kEncoderParameter, 0x6320, kGen | kMfg,
             "Module %2: encoder parameter combination refused (0x8nn0 subindex %4)"},
    DiagText{text::kEmergency, 0x0000, kGen, "Emergency 0x%4"},
    DiagText{text::kCpuOverTemperature, 0x4210, kGen | kTemp,
             "CPU zone temperature at or above the limit"},
    DiagText{text::kCpuFanError, 0x5000, kGen | kTemp, "CPU fan speed 30 % below nominal"},
    DiagText{text::kCpuFanFailure, 0x5000, kGen | kTemp,
             "CPU fan failure: speed 50 % below nominal"},
    DiagText{text::kWatchdog, 0x8110, kGen | kComm,
             "Process-data watchdog expired: outputs in their safe state"},
    DiagText{text::kRimOffline, 0xA001, kGen | kComm, "RIM %1 offline: its modules are missing"},
    DiagText{text::kRimCommError, 0x7500, kGen | kComm, "RIM %1 communication error"},
    DiagText{text::kSlotFanError, 0x5000, kGen | kTemp,
             "RIM %1 slot-card fan speed 30 % below nominal"},
    DiagText{text::kSlotFanFailure, 0x5000, kGen | kTemp,
             "RIM %1 slot-card fan failure: speed 50 % below nominal"},
    DiagText{text::kPsFanError, 0x5000, kGen | kTemp,
             "RIM %1 power-supply fan speed 30 % below nominal"},
    DiagText{text::kPsFanFailure, 0x5000, kGen | kTemp,
             "RIM %1 power-supply fan failure: speed 50 % below nominal"},
    DiagText{text::kSlotMachineMcm0, 0x6000, kGen | kMfg, "RIM %1 MCM 0 SLOT machine error"},
    DiagText{text::kSoutCompareMcm0, 0x6000, kGen | kMfg, "RIM %1 MCM 0 SOUT compare error"},
    DiagText{text::kSlotMachineMcm1, 0x6000, kGen | kMfg, "RIM %1 MCM 1 SLOT machine error"},
    DiagText{text::kSoutCompareMcm1, 0x6000, kGen | kMfg, "RIM %1 MCM 1 SOUT compare error"},
    DiagText{text::kUnsafeWiring, 0x2320, kGen | kCur | kMfg,
             "Module %2 channel %3: short circuit to supply (unsafe wiring fault)"},
    DiagText{text::kOverload, 0x2310, kGen | kCur | kMfg, "Module %2 channel %3: output overload"},
    DiagText{text::kOvertemperature, 0x4200, kGen | kTemp | kMfg,
             "Module %2 channel %3: overtemperature"},
    DiagText{text::kLineBreak, 0xFF06, kGen | kMfg,
             "Module %2 channel %3: line break (open sensor or loop)"},
    // CiA 301 emergency classes: 0x5000 device hardware, 0x7300 sensor, 0x8100 communication.
    DiagText{text::kEncoderHardware, 0x5000, kGen | kMfg,
             "Module %2: encoder hardware error (G1_XIST2 error code 0x%4)"},
    DiagText{text::kEncoderJump, 0x7300, kGen | kMfg,
             "Module %2: encoder position jump (G1_XIST2 error code 0x%4)"},
    DiagText{text::kEncoderFrozen, 0x7300, kGen | kMfg,
             "Module %2: encoder position frozen (G1_XIST2 error code 0x%4)"},
    DiagText{text::kEncoderLifeSign, 0x8100, kGen | kComm,
             "Module %2: master sign-of-life failures exceeded (G1_XIST2 error code 0x%4)"},
};

constexpr bool sorted_by_id() {
  for (size_t i = 1; i < kTexts.size(); ++i) {
    if (kTexts[i - 1].text_id >= kTexts[i].text_id) return false;
  }
  return true;
}
static_assert(sorted_by_id(), "catalogue in text ID order");

// RIM event bits (guide Table 16, modules/rack/events.hpp rim_event) to their text.
uint16_t rim_bit_text(unsigned bit) {
  switch (bit) {
    case 2:
      return text::kRimNotOnline;
    case 3:
      return text::kRimOffline;
    case 4:
      return text::kRimCommError;
    case 8:
      return text::kSlotFanWarning;
    case 9:
      return text::kSlotFanError;
    case 10:
      return text::kSlotFanFailure;
    case 12:
      return text::kPsFanWarning;
    case 13:
      return text::kPsFanError;
    case 14:
      return text::kPsFanFailure;
    case 16:
      return text::kSlotMachineMcm0;
    case 17:
      return text::kSoutCompareMcm0;
    case 18:
      return text::kSlotMachineMcm1;
    case 19:
      return text::kSoutCompareMcm1;
    default:
      return text::kEmergency;
  }
}

// Device event bits (guide Table 15: 0x2000:0A bits 8..10).
uint16_t device_bit_text(unsigned bit) {
  switch (bit) {
    case 8:
      return text::kCpuFanWarning;
    case 9:
      return text::kCpuFanError;
    case 10:
      return text::kCpuFanFailure;
    default:
      return text::kEmergency;
  }
}

}  // namespace

uint16_t channel_error_text(ChannelError e) {
  switch (e) {
    case ChannelError::ShortCircuit:
      return text::kUnsafeWiring;
    case ChannelError::Overload:
      return text::kOverload;
    case ChannelError::Overtemperature:
      return text::kOvertemperature;
    case ChannelError::LineBreak:
      return text::kLineBreak;
    case ChannelError::UpperLimit:
      return text::kUpperLimit;
    case ChannelError::LowerLimit:
      return text::kLowerLimit;
  }
  return text::kEmergency;
}

std::span<const DiagText> catalogue() {
  return kTexts;
}

const DiagText* find(uint16_t text_id) {
  const auto it = std::lower_bound(kTexts.begin(), kTexts.end(), text_id,
                                   [](const DiagText& t, uint16_t id) { return t.text_id < id; });
  return it != kTexts.end() && it->text_id == text_id ? &*it : nullptr;
}

uint16_t text_for_emergency(uint16_t code, std::span<const uint8_t, 5> data) {
  const uint8_t rim = data[0];
  const uint8_t module = data[1];
  const uint8_t bit = data[2];
  uint16_t appears = text::kEmergency;
  if (code == 0x0000 || code == 0x4210) {
    // Removed (or the CPU temperature): what it names decides.
    if (module != 0) {
      appears = text::kUnsafeWiring;
    } else if (rim != 0) {
      appears = rim_bit_text(bit);
    } else if (bit == 0xFF) {
      appears = text::kCpuOverTemperature;
    } else {
      appears = device_bit_text(bit);
    }
    if (code == 0x4210) return appears;
    return appears == text::kEmergency ? appears : removed_text(appears);
  }
  switch (code) {
    case 0x2320:
      return text::kUnsafeWiring;
    case 0x2330:
      return text::kSafeWiring;
    case 0x8110:
      return text::kWatchdog;
    case 0x5000:
      return rim != 0 ? rim_bit_text(bit) : device_bit_text(bit);
    case 0xA001:
    case 0x7500:
    case 0x6000:
      return rim_bit_text(bit);
    default:
      for (const DiagText& t : kTexts) {
        if (t.emergency_code == code && (t.text_id & 0xF000) != 0x1000) return t.text_id;
      }
      return text::kEmergency;
  }
}

std::string format(const DiagText& t, uint8_t rim, uint16_t module, uint8_t channel,
                   uint16_t detail) {
  std::string out;
  out.reserve(t.text.size() + 16);
  for (size_t i = 0; i < t.text.size(); ++i) {
    if (t.text[i] == '%' && i + 1 < t.text.size() && t.text[i + 1] >= '1' && t.text[i + 1] <= '4') {
      switch (t.text[++i]) {
        case '1':
          out += std::to_string(rim);
          break;
        case '2':
          out += std::to_string(module);
          break;
        case '3':
          out += channel == 0xFF ? std::string("-") : std::to_string(channel);
          break;
        default:
          // Emergency codes and the encoders' G1_XIST2 error codes read in hex.
          if (t.text_id == text::kEmergency ||
              (((t.text_id >> 8) & 0xF) == 8 && t.text_id != text::kEncoderParameter)) {
            char hex[8];
            std::snprintf(hex, sizeof hex, "%04X", detail);
            out += hex;
          } else {
            out += std::to_string(detail);
          }
      }
    } else {
      out += t.text[i];
    }
  }
  return out;
}

}  // namespace rackcat::mdp::diag
