// A PdiPort through a LAN9252's indirect access (LAN9252 datasheet §12.x "EtherCAT CSR and
// process data RAM access"), the way firmware on a microcontroller reaches that chip over SPI:
//   - EtherCAT core registers (0x0000-0x0FFF): one CSR access of 1, 2 or 4 bytes at a time -
//     data into ECAT_CSR_DATA 0x300 (writes), command busy | read | size | address into
//     ECAT_CSR_CMD 0x304, wait until busy clears, data out of ECAT_CSR_DATA (reads);
//   - process RAM (0x1000-): address and length into ECAT_PRAM_RD/WR_ADDR_LEN, busy into
//     ECAT_PRAM_RD/WR_CMD, then DWORDs through the read FIFO (0x000) or write FIFO (0x020) as
//     the command register reports them available; the first DWORD carries the first byte in
//     the lane of the start address (address & 3).
// The ESC's buffer semantics are the chip's: this class only moves bytes. It does not
// allocate. The transport (Lan9252Bus) is the SPI link.
#pragma once

#include <cstdint>
#include <span>

#include "ecat/lan9252/lan9252_bus.hpp"
#include "ecat/pdi_port.hpp"

namespace rackcat::ecat {

class Lan9252Pdi final : public PdiPort {
 public:
  // `bus` must outlive the port.
  explicit Lan9252Pdi(Lan9252Bus& bus) : bus_(bus) {}

  // Checks the chip is there and ready (BYTE_TEST 0x87654321, HW_CFG ready) and enables its
  // IRQ pin for the EtherCAT interrupt (INT_EN bit 0, IRQ_CFG bit 8). False: no chip answers.
  bool start();

  void read(uint16_t address, std::span<uint8_t> dst) override;
  void write(uint16_t address, std::span<const uint8_t> src) override;
  // A SyncManager buffer in process RAM is one PRAM FIFO transfer of the whole buffer: the
  // LAN9252 moves it between its FIFO and the EtherCAT core in address order, so the core's
  // first/last-byte rules open and complete the buffer (LAN9252 datasheet, "process data RAM
  // access"; ETG.1000.4 §6.7.2). A buffer in the register area goes byte-wise through the CSR.
  void read_buffer(uint8_t sm, uint16_t address, std::span<uint8_t> dst) override;
  void write_buffer(uint8_t sm, uint16_t address, std::span<const uint8_t> src) override;
  bool irq() const override { return bus_.irq(); }

  // Bus transactions so far (each SPI instruction counts once): what an access costs.
  uint64_t transactions() const { return transactions_; }

 private:
  uint32_t sys_read(uint16_t address);
  void sys_write(uint16_t address, uint32_t value);
  void csr_read(uint16_t address, uint8_t* dst, uint8_t size);
  void csr_write(uint16_t address, const uint8_t* src, uint8_t size);
  void pram_read(uint16_t address, uint8_t* dst, uint16_t len);
  void pram_write(uint16_t address, const uint8_t* src, uint16_t len);

  Lan9252Bus& bus_;
  uint64_t transactions_ = 0;
};

}  // namespace rackcat::ecat
