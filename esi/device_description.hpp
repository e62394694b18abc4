// What the SII image and the ESI file say about the device, in one value type. It is derived
// from the live object dictionary and the device's SyncManager plan (describe_device.hpp), so
// the EEPROM, the ESI and the dictionary cannot disagree; the encoders only format it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace rackcat::esi {

// SII SyncManager category type byte (ETG.2010 §2.6 Table 10).
enum class SmType : uint8_t {
  Unused = 0,
  MailboxOut = 1,  // master -> slave (receive mailbox, SM0)
  MailboxIn = 2,   // slave -> master (send mailbox, SM1)
  ProcessOut = 3,  // RxPDO outputs (SM2)
  ProcessIn = 4,   // TxPDO inputs (SM3)
};

// SII FMMU category usage byte (ETG.2010 §2.5 Table 9).
enum class FmmuUsage : uint8_t { Unused = 0, Outputs = 1, Inputs = 2, SmStatus = 3 };

struct SyncManagerDescription {
  SmType type = SmType::Unused;
  uint16_t start = 0;         // physical start address in ESC memory
  uint16_t default_size = 0;  // bytes with the current configuration
  uint16_t min_size = 0;
  uint16_t max_size = 0;
  uint8_t control = 0;  // SM control register 0x0804+8n (ETG.1000.4 Table 58)
  bool enable = true;   // SM activate register bit 0 at start-up
};

struct PdoEntryDescription {
  uint16_t index = 0;  // 0 = padding gap
  uint8_t subindex = 0;
  std::string name;
  uint16_t data_type = 0;  // CoE data type index (coe::DataType or enum 0x0800+)
  uint8_t bit_length = 0;
};

struct PdoDescription {
  uint16_t index = 0;  // 0x1600.. RxPDO, 0x1A00.. TxPDO
  std::string name;
  uint8_t sm = 0;        // SyncManager the PDO is assigned to
  bool assigned = true;  // in 0x1C12/0x1C13 now (SII/ESI "default" PDO)
  bool fixed = false;    // mapping object not writable
  bool mandatory = false;
  bool from_module = false;  // a slot's PDO: the ESI marks it OverwrittenByModule
  std::vector<PdoEntryDescription> entries;
};

// ESI Info/StateMachine/Timeout and Info/Mailbox/Timeout (ETG.2000 InfoType), milliseconds.
struct TimeoutDescription {
  int preop = 3000;           // INIT -> PREOP
  int safeop_op = 10000;      // PREOP -> SAFEOP and SAFEOP -> OP
  int back_to_init = 5000;    // any -> INIT
  int back_to_safeop = 200;   // OP -> SAFEOP
  int mailbox_request = 100;  // SM0 free for the next request
  int mailbox_response = 2000;
};

// One synchronisation mode (ETG.2010 §2.9 DC category, ETG.2000 Dc/OpMode).
struct DcOpModeDescription {
  std::string name;  // "FreeRun", "SM-Synchron", "DC"
  std::string description;
  uint16_t assign_activate = 0;  // value for register 0x0980 (0x0300 = SYNC0 active)
  uint32_t cycle_time_sync0 = 0;
  int16_t cycle_time_sync0_factor = 0;
  int32_t shift_time_sync0 = 0;
  int16_t cycle_time_sync1_factor = 0;
  int32_t shift_time_sync1 = 0;
};

// CoE features announced in the SII General category and ESI Mailbox/CoE (ETG.2010 Table 6).
struct CoeDetails {
  bool sdo = true;
  bool sdo_info = true;
  bool pdo_assign = true;
  bool pdo_config = true;
  bool upload_at_startup = false;
  bool complete_access = true;
  bool segmented_sdo = true;  // ESI only: the SII has no bit for it
  bool diag_history = true;   // ESI only: 0x10F3 diagnosis history (ETG.1020 ch. 13)
};

// Words 0..6 of the SII: the ESC configuration area loaded into registers at power-on
// (ETG.2010 §2.1; ESC datasheet "ESC Configuration Area").
struct EscConfigArea {
  // 0x0140 PDI control = 0x05 (SPI slave, the usual MCU connection); 0x0141 ESC configuration
  // = 0x0C (DC SYNC out unit and latch in unit enabled).
  uint16_t pdi_control = 0x0C05;
  // 0x0150 PDI configuration (SPI mode 0) and 0x0151 SYNC/LATCH configuration = 0x66: SYNC0 and
  // SYNC1 configured as push-pull active-high outputs.
  uint16_t pdi_config = 0x6600;
  uint16_t sync_impulse_length = 1000;  // 0x0982, in 10 ns units: 10 us
  uint16_t extended_pdi_config = 0x0000;
  uint16_t station_alias = 0x0000;  // 0x0012
};

// The bootstrap mailbox (SII words 0x14-0x17, ESI Eeprom/BootStrap; ETG.2010 Table 2): all 0
// for a device without BOOT state.
struct BootstrapMailbox {
  uint16_t receive_offset = 0, receive_size = 0;  // SM0 in BOOT
  uint16_t send_offset = 0, send_size = 0;        // SM1 in BOOT
};

struct DeviceDescription {
  // Identity, equal to 0x1018:01..04.
  uint32_t vendor_id = 0;
  uint32_t product_code = 0;
  uint32_t revision = 0;
  uint32_t serial = 0;

  std::string vendor_name;
  std::string device_name;  // 0x1008
  std::string order_code;   // ESI Device/Type text, SII order string
  std::string group_type;   // ESI GroupType / Group/Type
  std::string group_name;   // ESI Group/Name

  EscConfigArea config;
  CoeDetails coe;
  bool foe = false;  // FoE (SII word 0x1C bit 3, ESI Mailbox/FoE)
  BootstrapMailbox bootstrap;
  int16_t ebus_current_ma = 0;
  uint16_t physical_ports = 0x0011;  // ports 0 and 1 MII (ETG.2010 Table 6 "Physical Port")

  std::vector<SyncManagerDescription> sms;  // index = SM number
  std::vector<FmmuUsage> fmmus;
  std::vector<PdoDescription> rx_pdos;  // all RxPDOs the device offers
  std::vector<PdoDescription> tx_pdos;
  std::vector<DcOpModeDescription> dc_modes;
  TimeoutDescription timeouts;
};

}  // namespace rackcat::esi
