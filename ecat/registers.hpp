// ESC register addresses (ETG.1000.4 §6, Beckhoff ESC datasheet section II "Register
// description"). Only the registers the emulated ESC gives behaviour to are named here;
// docs/ESC.md describes what each one does.
#pragma once

#include <cstdint>

namespace rackcat::ecat::reg {

// Identification (read-only, ETG.1000.4 §6.1).
inline constexpr uint16_t kType = 0x0000;
inline constexpr uint16_t kRevision = 0x0001;
inline constexpr uint16_t kBuild = 0x0002;
inline constexpr uint16_t kFmmuCount = 0x0004;
inline constexpr uint16_t kSmCount = 0x0005;
inline constexpr uint16_t kRamSize = 0x0006;
inline constexpr uint16_t kPortDescriptor = 0x0007;
inline constexpr uint16_t kFeatures = 0x0008;
// Addressing (§6.2).
inline constexpr uint16_t kStationAddress = 0x0010;
inline constexpr uint16_t kStationAlias = 0x0012;
inline constexpr uint16_t kWriteEnable = 0x0020;
inline constexpr uint16_t kWriteProtection = 0x0021;
inline constexpr uint16_t kEscWriteEnable = 0x0030;
inline constexpr uint16_t kEscWriteProtection = 0x0031;
inline constexpr uint16_t kEscReset = 0x0040;
// Data link layer (§6.3).
inline constexpr uint16_t kDlControl = 0x0100;  // 4 bytes
inline constexpr uint16_t kPhysicalRwOffset = 0x0108;
inline constexpr uint16_t kDlStatus = 0x0110;
// Application layer (§6.4).
inline constexpr uint16_t kAlControl = 0x0120;
inline constexpr uint16_t kAlStatus = 0x0130;
inline constexpr uint16_t kAlStatusCode = 0x0134;
inline constexpr uint16_t kRunLedOverride = 0x0138;
inline constexpr uint16_t kErrLedOverride = 0x0139;
inline constexpr uint16_t kPdiControl = 0x0140;
inline constexpr uint16_t kEscConfig = 0x0141;
inline constexpr uint16_t kPdiConfig = 0x0150;
inline constexpr uint16_t kPdiConfigExt = 0x0152;
// Interrupts (§6.5).
inline constexpr uint16_t kEcatEventMask = 0x0200;
inline constexpr uint16_t kAlEventMask = 0x0204;
inline constexpr uint16_t kEcatEventRequest = 0x0210;
inline constexpr uint16_t kAlEventRequest = 0x0220;
// Error counters (§6.6).
inline constexpr uint16_t kRxErrorCounter = 0x0300;    // 2 bytes per port, 0x0300-0x0307
inline constexpr uint16_t kForwardedRxError = 0x0308;  // 1 byte per port, 0x0308-0x030B
inline constexpr uint16_t kProcessingUnitError = 0x030C;
inline constexpr uint16_t kPdiError = 0x030D;
inline constexpr uint16_t kLostLinkCounter = 0x0310;  // 1 byte per port, 0x0310-0x0313
// Watchdogs (§6.7).
inline constexpr uint16_t kWatchdogDivider = 0x0400;
inline constexpr uint16_t kWatchdogTimePdi = 0x0410;
inline constexpr uint16_t kWatchdogTimeProcessData = 0x0420;
inline constexpr uint16_t kWatchdogStatusProcessData = 0x0440;
inline constexpr uint16_t kWatchdogCounterProcessData = 0x0442;
inline constexpr uint16_t kWatchdogCounterPdi = 0x0443;
// SII EEPROM interface (§6.4.5).
inline constexpr uint16_t kSiiConfig = 0x0500;
inline constexpr uint16_t kSiiPdiAccess = 0x0501;
inline constexpr uint16_t kSiiControl = 0x0502;
inline constexpr uint16_t kSiiAddress = 0x0504;
inline constexpr uint16_t kSiiData = 0x0508;
// FMMU n at 0x0600 + 16 n, SyncManager n at 0x0800 + 8 n (§6.8, §6.9).
inline constexpr uint16_t kFmmu = 0x0600;
inline constexpr uint16_t kFmmuSize = 16;
inline constexpr uint16_t kSm = 0x0800;
inline constexpr uint16_t kSmSize = 8;
inline constexpr uint16_t kSmControlOffset = 4;
inline constexpr uint16_t kSmStatusOffset = 5;
inline constexpr uint16_t kSmActivateOffset = 6;
inline constexpr uint16_t kSmPdiControlOffset = 7;
// Distributed clocks (§6.10).
inline constexpr uint16_t kDcReceiveTimePort0 = 0x0900;           // 4 bytes per port
inline constexpr uint16_t kDcSystemTime = 0x0910;                 // 8 bytes
inline constexpr uint16_t kDcReceiveTimeProcessingUnit = 0x0918;  // 8 bytes
inline constexpr uint16_t kDcSystemTimeOffset = 0x0920;           // 8 bytes
inline constexpr uint16_t kDcSystemTimeDelay = 0x0928;            // 4 bytes
inline constexpr uint16_t kDcSystemTimeDifference = 0x092C;       // 4 bytes
inline constexpr uint16_t kDcSpeedCounterStart = 0x0930;
inline constexpr uint16_t kDcSpeedCounterDiff = 0x0932;
inline constexpr uint16_t kDcFilterDepth = 0x0934;
inline constexpr uint16_t kDcCyclicUnitControl = 0x0980;
inline constexpr uint16_t kDcActivation = 0x0981;
inline constexpr uint16_t kDcPulseLength = 0x0982;
inline constexpr uint16_t kDcActivationStatus = 0x0984;
inline constexpr uint16_t kDcSync0Status = 0x098E;
inline constexpr uint16_t kDcSync1Status = 0x098F;
inline constexpr uint16_t kDcStartTime = 0x0990;  // write: start time; read: next SYNC0 pulse
inline constexpr uint16_t kDcNextSync1 = 0x0998;
inline constexpr uint16_t kDcSync0Cycle = 0x09A0;
inline constexpr uint16_t kDcSync1Cycle = 0x09A4;
// Process RAM starts after the register block.
inline constexpr uint32_t kProcessRam = 0x1000;
inline constexpr uint32_t kAddressSpace = 0x10000;

// SyncManager n's registers and the bits of its control and status bytes (ETG.1000.4 §6.7.2
// Table 58; the same on the EtherCAT and the PDI side).
namespace sm {
constexpr uint16_t base(int n) {
  return static_cast<uint16_t>(kSm + kSmSize * n);
}
// Control: bits 1:0 mode (00 buffered, 10 mailbox), bits 3:2 direction (00 ECAT reads / PDI
// writes, 01 ECAT writes / PDI reads), bit 4 ECAT event enable, bit 5 AL event enable, bit 6
// watchdog trigger enable.
constexpr bool is_mailbox(uint8_t control) {
  return (control & 0x03) == 0x02;
}
constexpr bool ecat_writes(uint8_t control) {
  return (control & 0x0C) == 0x04;
}
inline constexpr uint8_t kControlAlEvent = 0x20;
inline constexpr uint8_t kControlWatchdog = 0x40;
// Status: bit 0 "interrupt write" (buffer completely written), bit 1 "interrupt read" (buffer
// completely read), bit 3 mailbox full, bits 5:4 last written buffer (11 = none), bit 6 read
// buffer open, bit 7 write buffer open (first byte accessed, last byte not yet).
inline constexpr uint8_t kStatusWritten = 0x01;
inline constexpr uint8_t kStatusRead = 0x02;
inline constexpr uint8_t kStatusFull = 0x08;
inline constexpr uint8_t kStatusNoBuffer = 0x30;
inline constexpr uint8_t kStatusReadOpen = 0x40;
inline constexpr uint8_t kStatusWriteOpen = 0x80;
// Activation (ECAT): bit 0 enable, bit 1 repeat request. PDI control: bit 0 deactivate, bit 1
// repeat acknowledge (ETG.1000.4 §6.7.3).
inline constexpr uint8_t kActivateEnable = 0x01;
inline constexpr uint8_t kRepeatRequest = 0x02;
inline constexpr uint8_t kPdiDeactivate = 0x01;
inline constexpr uint8_t kRepeatAck = 0x02;
}  // namespace sm

}  // namespace rackcat::ecat::reg
