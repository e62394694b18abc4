// The device's fixed SyncManager plan. The SII (esi/), the ESI (esi/), the ESM checks (ecat/
// through ecat::Application) and the object dictionary (0x1C00, 0x1C32/0x1C33) all read these
// constants, so they cannot disagree. Control bytes per ETG.1000.4 §6.7.2 Table 60 (bits 1..0
// mode: 00 buffered, 10 mailbox; bits 3..2 direction: 00 read by master, 01 written by master;
// bit 5 PDI interrupt, bit 6 watchdog trigger). Docs: docs/MDP.md "SyncManagers and PDO
// indices".
#pragma once

#include <cstdint>

namespace rackcat::mdp::sm {

// SM0: mailbox out (master -> slave, "receive mailbox" in SII words 0x18/0x19).
inline constexpr uint16_t kMailboxOutStart = 0x1000;
inline constexpr uint16_t kMailboxOutSize = 128;
inline constexpr uint8_t kMailboxOutControl = 0x26;  // mailbox, written by master, PDI irq
// SM1: mailbox in (slave -> master, "send mailbox" in SII words 0x1A/0x1B).
inline constexpr uint16_t kMailboxInStart = 0x1080;
inline constexpr uint16_t kMailboxInSize = 128;
inline constexpr uint8_t kMailboxInControl = 0x22;  // mailbox, read by master, PDI irq
// The bootstrap mailbox (BOOT state, ETG.1000.6 §5.3; SII words 0x14-0x17, ESI Eeprom/BootStrap):
// SM0 and SM1 of their own, sized by the rack (ControlModule::boot_mailbox_size, default
// kBootMailboxSize, at most kMaxMailboxSize: one datagram in one frame).
inline constexpr uint16_t kBootMailboxOutStart = 0x1000;
inline constexpr uint16_t kBootMailboxInStart = 0x1600;
inline constexpr uint16_t kBootMailboxSize = 512;
inline constexpr uint16_t kMaxMailboxSize = 1486;
inline constexpr uint16_t kMinMailboxSize = 64;
// SM2: process data outputs (RxPDOs, 0x1C12).
inline constexpr uint16_t kOutputsStart = 0x1100;
inline constexpr uint8_t kOutputsControl = 0x64;  // buffered, written by master, irq, watchdog
// SM3: process data inputs (TxPDOs, 0x1C13).
inline constexpr uint16_t kInputsStart = 0x5100;
inline constexpr uint8_t kInputsControl = 0x20;  // buffered, read by master, PDI irq
// Largest process-data image per direction; a PDO assignment that exceeds it is refused with
// SDO abort 0x06040042 (0x1C12/0x1C13 write) and never reaches the SM configuration.
inline constexpr uint16_t kMaxProcessDataBytes = 0x4000;

// SII SyncManager category type byte (ETG.2010 Table 15) and 0x1C00 communication type
// (ETG.1000.6 §5.6.7.4.9): 1 mailbox out, 2 mailbox in, 3 outputs, 4 inputs.
inline constexpr uint8_t kTypeMailboxOut = 1;
inline constexpr uint8_t kTypeMailboxIn = 2;
inline constexpr uint8_t kTypeOutputs = 3;
inline constexpr uint8_t kTypeInputs = 4;

// PDO index rule (ETG.5001.1 "PdoIndexIncrement" style, one PDO per module and direction):
// module n (1..255) has its RxPDO mapping object at 0x1600 + n - 1 when its card has outputs
// and its TxPDO mapping object at 0x1A00 + n - 1 when its card has inputs. Modules without
// outputs (inputs) have no object at that RxPDO (TxPDO) index.
inline constexpr uint16_t kRxPdoBase = 0x1600;
inline constexpr uint16_t kTxPdoBase = 0x1A00;
inline constexpr uint16_t kPdoIndexIncrement = 1;
constexpr uint16_t rx_pdo_index(uint16_t module_number) {
  return static_cast<uint16_t>(kRxPdoBase + (module_number - 1) * kPdoIndexIncrement);
}
constexpr uint16_t tx_pdo_index(uint16_t module_number) {
  return static_cast<uint16_t>(kTxPdoBase + (module_number - 1) * kPdoIndexIncrement);
}

// User PDOs (guide §2.6/§4.8: the thermocouple ohms and 0x2000:0F are "user-PDO mappable",
// "mapped in by the EtherCAT operator"; Appendix A flags further TX/RX entries): one RxPDO and
// one TxPDO after the module range, empty and unassigned by default, whose mapping the master
// writes in PREOP (ETG.1000.6 §5.6.7.4.8) and then adds to 0x1C12/0x1C13.
inline constexpr uint16_t kUserRxPdo = 0x1700;
inline constexpr uint16_t kUserTxPdo = 0x1B00;
inline constexpr uint8_t kUserPdoEntries = 32;

}  // namespace rackcat::mdp::sm
