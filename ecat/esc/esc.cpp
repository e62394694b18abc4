// ESC core: power-on state, the datagram engine for one slave (ETG.1000.4 §5.4) and physical
// memory access through the SyncManager and register rules.
#include "ecat/esc/esc.hpp"

#include <algorithm>
#include <array>
#include <cstring>

#include "base/little_endian.hpp"
#include "ecat/frame.hpp"
#include "ecat/registers.hpp"

namespace rackcat::ecat {

namespace {

// ECAT event request bits (0x0210, ETG.1000.4 §6.5).
constexpr uint16_t kEventDlStatus = 0x0004;

}  // namespace

Esc::Esc(SiiEeprom& eeprom, const Clock& clock, EscOptions options)
    : eeprom_(eeprom), clock_(clock), options_(options) {
  if (options_.sii_read_bytes != 4) options_.sii_read_bytes = 8;
  sii_load_image();
  power_on_reset();
}

void Esc::power_on_reset() {
  mem_.reset();  // registers zero, process RAM back to the kernel (reads 0)
  // Identification (read-only).
  mem_[reg::kType] = options_.type;
  mem_[reg::kRevision] = options_.revision;
  le::put16(&mem_[reg::kBuild], options_.build);
  mem_[reg::kFmmuCount] = kFmmus;
  mem_[reg::kSmCount] = kSyncManagers;
  mem_[reg::kRamSize] = (kMemorySize - reg::kProcessRam) / 1024;  // KiB of process RAM
  mem_[reg::kPortDescriptor] = options_.port_descriptor;
  le::put16(&mem_[reg::kFeatures], options_.features);
  // DL control reset value: forwarding rule 1 (non-EtherCAT frames destroyed), loops auto,
  // RX FIFO size 7 (datasheet reset value 0x00070001).
  le::put32(&mem_[reg::kDlControl], 0x00070001);
  // Watchdog reset values: divider 2498 (100 µs), PDI and process-data watchdog 1000 (100 ms).
  le::put16(&mem_[reg::kWatchdogDivider], 0x09C2);
  le::put16(&mem_[reg::kWatchdogTimePdi], 0x03E8);
  le::put16(&mem_[reg::kWatchdogTimeProcessData], 0x03E8);
  mem_[reg::kWatchdogStatusProcessData] = 0x01;  // active or disabled, not expired
  // DC control loop reset values.
  le::put16(&mem_[reg::kDcSpeedCounterStart], 0x1000);
  mem_[reg::kDcFilterDepth] = 0x04;
  mem_[reg::kDcFilterDepth + 1] = 0x0C;
  // AL control and AL status reset values: 0x01 (INIT), no error (ESC datasheet 0x0120,
  // 0x0130); from here on the firmware writes AL status.
  mem_[reg::kAlControl] = 0x01;
  mem_[reg::kAlStatus] = 0x01;

  reset_signal_ = true;
  sync0_running_ = sync1_running_ = false;
  watchdog_armed_ = false;
  watchdog_running_ = true;
  derive_write_protection();
  derive_watchdog_period();
  reset_sequence_ = 0;
  local_offset_ = options_.power_on_local_time_ns - clock_.now_ns();

  sm_.fill(SmState{});
  activate_seen_.fill(0);
  sm_enabled_mask_ = 0;
  sm_alone_mask_ = 0;
  sm_first_byte_ = reg::kAddressSpace;
  // PDI control 0x0807 resets to "deactivated" (the firmware activates what its state allows,
  // ETG.1000.6 §5.3); status "no buffer written".
  for (int i = 0; i < kSyncManagers; ++i) {
    mem_[reg::kSm + reg::kSmSize * i + reg::kSmPdiControlOffset] = 0x01;
    mem_[reg::kSm + reg::kSmSize * i + reg::kSmStatusOffset] = 0x30;  // no buffer written
  }
  fmmu_.fill(FmmuState{});
  fmmu_active_mask_ = 0;
  fmmu_meeting_known_ = 0;
  fmmu_whole_mask_ = 0;
  forget_whole_plans();
  if (fmmu_generation_ != nullptr) ++*fmmu_generation_;

  sii_reload_config_area();
  set_port1_link(port1_link_);
}

bool Esc::take_reset() {
  const bool reset = reset_signal_;
  reset_signal_ = false;
  return reset;
}

void Esc::set_port1_link(bool link) {
  port1_link_ = link;
  // DL control 0x0101 bits 3:2 = loop control of port 1 (ETG.1000.4 §6.3.1): 00 auto, 01
  // auto-close, 10 open, 11 closed. Auto modes open the port when a link is present.
  const uint8_t loop = (mem_[reg::kDlControl + 1] >> 2) & 0x03;
  forwards_port1_ = loop == 0x02 || (loop != 0x03 && port1_link_);
  // DL status 0x0110 (ETG.1000.4 Table 31): bit 0 PDI operational (EEPROM loaded), bit 1 PDI
  // watchdog not expired, bits 4-7 physical link, then per port n bit 8+2n "loop closed" and
  // bit 9+2n "communication established". Ports 2 and 3 do not exist: loop closed, no link.
  const uint16_t sii_status = le::get16(&mem_[reg::kSiiControl]);
  uint16_t status = 0;
  if ((sii_status & 0x1800) == 0) status |= 0x0001;
  status |= 0x0002;
  status |= 0x0010 | 0x0200;  // port 0: link, communication, loop open
  if (port1_link_) status |= 0x0020 | 0x0800;
  if (!forwards_to_port1()) status |= 0x0400;
  status |= 0x1000 | 0x4000;
  const uint16_t old = le::get16(&mem_[reg::kDlStatus]);
  if (old != status) {
    le::put16(&mem_[reg::kDlStatus], status);
    le::put16(&mem_[reg::kEcatEventRequest],
              le::get16(&mem_[reg::kEcatEventRequest]) | kEventDlStatus);
  }
}

bool Esc::addressed_by_station(uint16_t adp) const {
  if (adp == le::get16(&mem_[reg::kStationAddress])) return true;
  // DL control bit 24 (0x0103 bit 0) lets the configured station alias address us too.
  return (mem_[reg::kDlControl + 3] & 0x01) && adp == le::get16(&mem_[reg::kStationAlias]);
}

void Esc::process_datagram(uint8_t* datagram, uint16_t data_len) {
  const uint8_t command = datagram[0];
  uint8_t* data = datagram + kDatagramHeaderSize;
  const uint16_t adp = le::get16(datagram + 2);
  const uint16_t ado = le::get16(datagram + 4);
  uint8_t wkc = 0;
  bool physical = true;
  bool addressed = false;
  switch (static_cast<Command>(command)) {
    case Command::Aprd:
    case Command::Apwr:
    case Command::Aprw:
    case Command::Armw:
      // Position addressing: the slave that sees ADP 0 is addressed; every slave increments
      // ADP on the way (ETG.1000.4 §5.3.2).
      le::put16(datagram + 2, static_cast<uint16_t>(adp + 1));
      addressed = adp == 0;
      break;
    case Command::Fprd:
    case Command::Fpwr:
    case Command::Fprw:
    case Command::Frmw:
      addressed = addressed_by_station(adp);
      break;
    case Command::Brd:
    case Command::Bwr:
    case Command::Brw:
      le::put16(datagram + 2, static_cast<uint16_t>(adp + 1));
      addressed = true;
      break;
    case Command::Lrd:
    case Command::Lwr:
    case Command::Lrw:
      wkc = process_logical(command, le::get32(datagram + 2), data, data_len, fmmu_active_mask_);
      physical = false;
      break;
    default:
      physical = false;  // NOP, reserved commands: the ESC forwards the datagram untouched
      break;
  }
  const auto cmd = static_cast<Command>(command);
  // Read-multiple-write: the addressed slave reads, every other slave writes (§5.4.3); the
  // other commands only act where they address.
  if (physical && (addressed || cmd == Command::Armw || cmd == Command::Frmw)) {
    wkc = process_physical(command, ado, data, data_len, addressed);
  }
  leave_datagram(datagram, data_len, wkc);
}

void Esc::pass_datagram(uint8_t* datagram) const {
  or_irq(datagram);
}

void Esc::or_irq(uint8_t* datagram) const {
  // IRQ field: ECAT event request ANDed with the ECAT event mask, ORed in by every slave
  // (ETG.1000.4 §5.4, Table 12 "IRQ").
  const uint16_t events =
      le::get16(&mem_[reg::kEcatEventRequest]) & le::get16(&mem_[reg::kEcatEventMask]);
  if (events != 0) le::put16(datagram + 8, le::get16(datagram + 8) | events);
}

uint8_t Esc::process_physical(uint8_t command, uint16_t address, uint8_t* data, uint16_t len,
                              bool addressed) {
  const auto cmd = static_cast<Command>(command);
  // An access crossing the end of the 64 KiB address space is ignored (no WKC).
  if (static_cast<uint32_t>(address) + len > reg::kAddressSpace) return 0;
  switch (cmd) {
    case Command::Aprd:
    case Command::Fprd:
      return physical_read(address, data, len, false) ? 1 : 0;
    case Command::Brd:
      return physical_read(address, data, len, true) ? 1 : 0;
    case Command::Apwr:
    case Command::Fpwr:
    case Command::Bwr:
      return physical_write(address, data, len) ? 1 : 0;
    case Command::Aprw:
    case Command::Fprw:
    case Command::Brw:
      return physical_read_write(address, data, len, cmd == Command::Brw);
    case Command::Armw:
    case Command::Frmw:
      // Read-multiple-write: the addressed slave reads, every other slave writes (§5.4.3).
      if (addressed) return physical_read(address, data, len, false) ? 1 : 0;
      return physical_write(address, data, len) ? 1 : 0;
    default:
      return 0;
  }
}

uint8_t* Esc::datagram_scratch() {
  alignas(base::kCacheLine) static thread_local std::array<uint8_t, kDatagramScratch> scratch{};
  return scratch.data();
}

uint8_t Esc::physical_read_write(uint16_t address, uint8_t* data, uint16_t len, bool merge_or) {
  // The datagram returns the old content (ORed for BRW) while the incoming data is written;
  // WKC +1 for the read, +2 for the write (ETG.1000.4 §5.4.4).
  if (len > kDatagramScratch) return 0;  // longer than any frame carries
  uint8_t* const incoming = datagram_scratch();
  std::memcpy(incoming, data, len);
  const bool r = physical_read(address, data, len, merge_or);
  const bool w = physical_write(address, incoming, len);
  return static_cast<uint8_t>((r ? 1 : 0) + (w ? 2 : 0));
}

bool Esc::generic_read(uint16_t address, uint8_t* dst, uint16_t len, bool merge_or) {
  const uint32_t end = static_cast<uint32_t>(address) + len;
  const uint16_t meeting = sm_meeting(address, end);
  if (!sm_allows_read(meeting)) return false;
  const uint16_t reg_len =
      address < reg::kProcessRam
          ? static_cast<uint16_t>(std::min<uint32_t>(end, reg::kProcessRam) - address)
          : 0;
  if (reg_len != 0) before_register_read(address, reg_len);
  const uint8_t* src = &mem_[address];
  if (merge_or) {
    for (uint16_t i = 0; i < len; ++i) dst[i] |= src[i];
  } else {
    std::memcpy(dst, src, len);
  }
  sm_after_read(meeting, address, len);
  if (reg_len != 0) after_register_read(address, reg_len);
  return true;
}

bool Esc::generic_write(uint16_t address, const uint8_t* src, uint16_t len) {
  const uint16_t meeting = sm_meeting(address, static_cast<uint32_t>(address) + len);
  if (!sm_allows_write(meeting)) return false;
  if (write_protection_active()) return protected_write(address, src, len);
  uint16_t done = 0;
  if (address < reg::kProcessRam) {
    done = static_cast<uint16_t>(
        std::min<uint32_t>(static_cast<uint32_t>(address) + len, reg::kProcessRam) - address);
    write_registers(address, src, done);
    after_register_write(address, src, done);
  }
  if (done < len) std::memcpy(&mem_[address + done], src + done, len - done);
  // A register write may have (re)configured a SyncManager: look them up again then.
  sm_after_write(done != 0 ? sm_meeting(address, static_cast<uint32_t>(address) + len) : meeting,
                 address, len);
  return true;
}

void Esc::count_frame_error() {
  // ESC datasheet 0x030C: "ECAT processing unit error counter", 0x0300: port 0 invalid frame
  // counter; both saturate at 0xFF.
  if (mem_[reg::kProcessingUnitError] != 0xFF) ++mem_[reg::kProcessingUnitError];
  if (mem_[reg::kRxErrorCounter] != 0xFF) ++mem_[reg::kRxErrorCounter];
}

bool Esc::al_error() const {
  return (mem_[reg::kAlStatus] & 0x10) != 0;
}
uint16_t Esc::al_status_code() const {
  return le::get16(&mem_[reg::kAlStatusCode]);
}
uint16_t Esc::station_address() const {
  return le::get16(&mem_[reg::kStationAddress]);
}
uint16_t Esc::read16(uint16_t address) const {
  return static_cast<uint16_t>(mem_[address] | mem_[static_cast<uint16_t>(address + 1)] << 8);
}
uint32_t Esc::read32(uint16_t address) const {
  return read16(address) | static_cast<uint32_t>(read16(static_cast<uint16_t>(address + 2))) << 16;
}
uint64_t Esc::read64(uint16_t address) const {
  return read32(address) | static_cast<uint64_t>(read32(static_cast<uint16_t>(address + 4))) << 32;
}

}  // namespace rackcat::ecat
