// The process data interface (PDI) of an ESC as the slave's microcontroller sees it: byte
// reads and writes of the ESC address space (registers 0x0000-0x0FFF, process RAM from
// 0x1000) and one interrupt line. This is the only thing the firmware (ecat/slave) knows of
// the chip. Behind it sit the emulated ESC (ecat/esc, EscPdi) or a real one reached through a
// bus, e.g. a LAN9252 over SPI.
//
// What a PDI access does is the ESC's business, not the port's (ETG.1000.4 §6, ESC datasheet
// section II "PDI access"): reading the first byte of a SyncManager buffer the master wrote
// clears its event, reading its last byte frees a mailbox, writing the last byte of a buffer
// the master reads hands it over; reading AL control 0x0120 clears AL event request bit 0.
// The firmware relies on exactly those side effects, as it would on a real chip. A whole
// SyncManager buffer may go in one block access (read_buffer/write_buffer) with the same rules.
#pragma once

#include <cstdint>
#include <span>

#include "base/little_endian.hpp"

namespace rackcat::ecat {

class PdiPort {
 public:
  virtual ~PdiPort() = default;

  // One access of `dst.size()` / `src.size()` bytes at `address`, in address order.
  virtual void read(uint16_t address, std::span<uint8_t> dst) = 0;
  virtual void write(uint16_t address, std::span<const uint8_t> src) = 0;
  // One whole SyncManager buffer in one access: SM `sm`'s buffer starting at `address`, as
  // many bytes as it holds (ETG.1000.4 §6.7.2; how a firmware moves SM2 outputs and SM3 inputs
  // each cycle, and SM0/SM1 mailboxes). The ESC applies what it applies to those bytes read or
  // written one after the other: the first byte opens the buffer, the last completes it - a
  // read releases it (a mailbox is emptied; buffered: the next read opens the newest buffer),
  // a write hands it over (a mailbox is full; buffered: the three-buffer exchange makes it the
  // newest). A port may do it faster than the byte-wise access (the emulated ESC finds the SM
  // without a search, a LAN9252 moves it in one PRAM FIFO transfer); by default it is that.
  virtual void read_buffer(uint8_t sm, uint16_t address, std::span<uint8_t> dst) {
    static_cast<void>(sm);
    read(address, dst);
  }
  virtual void write_buffer(uint8_t sm, uint16_t address, std::span<const uint8_t> src) {
    static_cast<void>(sm);
    write(address, src);
  }
  // The IRQ line: AL event request 0x0220 ANDed with the AL event mask 0x0204 is non-zero
  // (ETG.1000.4 §6.5 "interrupts").
  virtual bool irq() const = 0;

  uint8_t read8(uint16_t address) {
    uint8_t v = 0;
    read(address, std::span<uint8_t>(&v, 1));
    return v;
  }
  uint16_t read16(uint16_t address) {
    uint8_t b[2];
    read(address, b);
    return le::get16(b);
  }
  uint32_t read32(uint16_t address) {
    uint8_t b[4];
    read(address, b);
    return le::get32(b);
  }
  uint64_t read64(uint16_t address) {
    uint8_t b[8];
    read(address, b);
    return le::get64(b);
  }
  void write8(uint16_t address, uint8_t v) { write(address, std::span<const uint8_t>(&v, 1)); }
  void write16(uint16_t address, uint16_t v) {
    uint8_t b[2];
    le::put16(b, v);
    write(address, b);
  }
  void write32(uint16_t address, uint32_t v) {
    uint8_t b[4];
    le::put32(b, v);
    write(address, b);
  }
};

}  // namespace rackcat::ecat
