// The ESC's PDI side: what the microcontroller's register reads and writes do (ETG.1000.4 §6,
// Beckhoff ESC datasheet section II, "PDI" columns of each register).
//
// Registers. The PDI writes AL status 0x0130 (raising ECAT event 0x0210 bit 3 for the master),
// AL status code 0x0134, the AL event mask 0x0204, the PDI control byte of each SyncManager
// (0x0807+8n: bit 0 deactivate, bit 1 repeat acknowledge) and the user RAM 0x0F80; everything
// else is read-only for it. Reads clear the AL event they announce: 0x0120 (AL control) bit 0,
// an SM activation register 0x0806+8n bit 4, 0x0440 (watchdog status) bit 6, 0x098E/0x098F
// (SYNC0/1 status, also cleared) bits 2/3.
//
// SII EEPROM interface (ESC datasheet 0x0500-0x050F, ETG.1000.4 §6.4.5): the PDI may take the
// EEPROM (0x0501 bit 0) once the master offers it (0x0500 bit 0); while both bits are set the
// interface is the PDI's: it writes control/command 0x0502-0x0503, address 0x0504 and data
// 0x0508 and the master's writes there are ignored (sii.cpp). A microcontroller uses this to
// store a new EEPROM content, e.g. after a firmware update.
//
// SyncManager buffers, seen from the PDI (ETG.1000.4 §6.7.1/§6.7.2; the rules are the same
// for both sides, sync_manager.cpp sm_buffer_access):
//   - a buffer the master writes (SM0 mailbox, SM2 outputs): reading its first byte opens it
//     (clears the "written" status and AL event bit 8+n); reading its last byte completes the
//     read: a mailbox is emptied (full flag off, "read" on, ECAT event for the master: it may
//     write again), a buffered SM releases the buffer (the three-buffer exchange: the next read
//     opens the newest buffer the master completed). A read that stops short of the last byte
//     leaves the buffer open (status bit 6) and switches nothing;
//   - a buffer the master reads (SM1 mailbox, SM3 inputs): writing its first byte opens it
//     (clears "read" and AL event bit 8+n); writing its last byte hands it to the master
//     (mailbox full; buffered: the newest of the three buffers, its index in status bits 5:4).
//     A full mailbox refuses PDI writes.
//   A SyncManager that is disabled or deactivated takes no PDI buffer access either.
//   pdi_read_buffer/pdi_write_buffer (esc.hpp) are the same access for one whole buffer: a
//   firmware's SM2 read and SM3 write each cycle, without looking for the SyncManager. A read
//   of registers without a read side effect (the AL event request among them) is a plain copy
//   there too (Esc::pdi_read); pdi_read_access below does the rest.
//   The emulated ESC keeps one image per buffered SM: the datagram engine and the PDI run one
//   after the other, never inside each other's access, so a complete access sees what the
//   three buffers of a real ESC would give it.
#include <algorithm>
#include <cstring>

#include "base/little_endian.hpp"
#include "base/short_copy.hpp"
#include "ecat/esc/esc.hpp"
#include "ecat/registers.hpp"

namespace rackcat::ecat {

namespace {

namespace sm = reg::sm;

constexpr bool overlaps(uint32_t address, uint32_t len, uint32_t reg_address, uint32_t reg_len) {
  return address < reg_address + reg_len && reg_address < address + len;
}

// PDI-writable bits of the register block (ESC datasheet "PDI access" column).
constexpr uint8_t pdi_write_mask(uint16_t a) {
  if (a == reg::kAlStatus) return 0x1F;  // state bits 3..0, error flag bit 4
  if (a == reg::kAlStatusCode || a == reg::kAlStatusCode + 1) return 0xFF;
  if (a >= reg::kAlEventMask && a < reg::kAlEventMask + 4) return 0xFF;
  if (a >= reg::kSm && a < reg::kSm + reg::kSmSize * 16 && (a & 7) == reg::kSmPdiControlOffset) {
    return sm::kPdiDeactivate | sm::kRepeatAck;
  }
  if (a >= 0x0F80 && a < reg::kProcessRam) return 0xFF;  // user RAM
  return 0x00;
}

}  // namespace

bool Esc::pdi_irq() const {
  return (le::get32(&mem_[reg::kAlEventRequest]) & le::get32(&mem_[reg::kAlEventMask])) != 0;
}

void Esc::pdi_read_access(uint16_t address, uint8_t* dst, uint16_t len) {
  len = static_cast<uint16_t>(std::min<uint32_t>(len, reg::kAddressSpace - address));
  if (len == 0) return;
  base::copy_bytes(dst, &mem_[address], len);
  if (address < reg::kProcessRam) pdi_registers_read(address, len);
  pdi_buffer_read_done(address, len);
}

void Esc::pdi_write(uint16_t address, const uint8_t* src, uint16_t len) {
  len = static_cast<uint16_t>(std::min<uint32_t>(len, reg::kAddressSpace - address));
  if (len == 0) return;
  if (address < reg::kProcessRam) {
    const uint16_t n =
        static_cast<uint16_t>(std::min<uint32_t>(address + len, reg::kProcessRam) - address);
    const bool sii_owned = sii_assigned_to_pdi();
    for (uint16_t i = 0; i < n; ++i) {
      const auto a = static_cast<uint16_t>(address + i);
      const uint8_t mask = a >= reg::kSiiPdiAccess && a < reg::kSiiData + 8
                               ? sii_pdi_write_mask(a, sii_owned)
                               : pdi_write_mask(a);
      mem_[a] = static_cast<uint8_t>((mem_[a] & ~mask) | (src[i] & mask));
    }
    pdi_registers_written(address, src, n, sii_owned);
    if (n == len) return;
    address = static_cast<uint16_t>(address + n);
    src += n;
    len = static_cast<uint16_t>(len - n);
  }
  pdi_buffer_write(address, src, len);
}

void Esc::pdi_registers_read(uint16_t address, uint16_t len) {
  // Nothing between AL control and the watchdog status clears an event (0x0220, 0x0130...).
  if (address >= reg::kAlControl + 2 &&
      static_cast<uint32_t>(address) + len <= reg::kWatchdogStatusProcessData) {
    return;
  }
  uint32_t clear = 0;
  if (overlaps(address, len, reg::kAlControl, 2)) clear |= 0x01u;
  if (overlaps(address, len, reg::kWatchdogStatusProcessData, 2)) clear |= 0x40u;
  if (overlaps(address, len, reg::kDcSync0Status, 1)) {
    clear |= 0x04u;
    mem_[reg::kDcSync0Status] &= static_cast<uint8_t>(~0x01);
  }
  if (overlaps(address, len, reg::kDcSync1Status, 1)) {
    clear |= 0x08u;
    mem_[reg::kDcSync1Status] &= static_cast<uint8_t>(~0x01);
  }
  if (overlaps(address, len, reg::kSm, reg::kSmSize * kSyncManagers)) {
    for (int n = 0; n < kSyncManagers; ++n) {
      if (overlaps(address, len, sm::base(n) + reg::kSmActivateOffset, 1)) clear |= 0x10u;
    }
  }
  if (clear != 0) {
    le::put32(&mem_[reg::kAlEventRequest], le::get32(&mem_[reg::kAlEventRequest]) & ~clear);
  }
}

void Esc::pdi_registers_written(uint16_t address, const uint8_t* src, uint16_t len,
                                bool sii_owned) {
  if (sii_owned && overlaps(address, len, reg::kSiiControl + 1, 1)) {
    // The command runs once the whole access is written (address and data written with it).
    const bool lo = overlaps(address, len, reg::kSiiControl, 1);
    sii_command(lo ? src[reg::kSiiControl - address] : 0,
                src[reg::kSiiControl + 1 - address] & 0x07, lo);
  }
  if (overlaps(address, len, reg::kAlStatus, 2)) {
    // AL status event for the master (ECAT event request 0x0210 bit 3), cleared when the
    // master reads 0x0130 (register_map.cpp).
    le::put16(&mem_[reg::kEcatEventRequest], le::get16(&mem_[reg::kEcatEventRequest]) | 0x0008);
  }
  if (overlaps(address, len, reg::kSm, reg::kSmSize * kSyncManagers)) {
    for (int n = 0; n < kSyncManagers; ++n) {
      if (overlaps(address, len, sm::base(n) + reg::kSmPdiControlOffset, 1)) reload_sm(n);
    }
  }
}

void Esc::pdi_buffer_read_done(uint16_t address, uint16_t len) {
  const uint32_t end = static_cast<uint32_t>(address) + len;
  for_each_sm_meeting(address, end, [&](int n) {
    // The PDI drains the buffers the master writes (SM0 mailbox, SM2 outputs).
    if (sm_[n].active && sm::ecat_writes(sm_[n].control)) sm_buffer_access(n, address, end, false);
  });
}

bool Esc::pdi_buffer_write(uint16_t address, const uint8_t* src, uint16_t len) {
  const uint32_t end = static_cast<uint32_t>(address) + len;
  bool allowed = true;
  for_each_sm_meeting(address, end, [&](int n) {
    // The PDI fills only the buffers the master reads, and a mailbox only once it is empty.
    if (sm::ecat_writes(sm_[n].control) || !sm_takes_write(n)) allowed = false;
  });
  if (!allowed) return false;
  std::memcpy(&mem_[address], src, len);
  for_each_sm_meeting(address, end, [&](int n) { sm_buffer_access(n, address, end, true); });
  return true;
}

}  // namespace rackcat::ecat
