// The emulated ESC behind a LAN9252's host bus: the chip model wrapped in the access protocol
// of that chip (LAN9252 datasheet Table 5-1 and "EtherCAT CSR and process data RAM access"),
// so the firmware can reach it through Lan9252Pdi exactly as it would reach a LAN9252 over
// SPI. System registers: BYTE_TEST, HW_CFG (ready), ID_REV, INT_EN/INT_STS/IRQ_CFG (the
// EtherCAT interrupt is the ESC's PDI IRQ), the CSR command/data pair and the two PRAM
// FIFOs. Accesses complete at once: busy reads back clear, a started PRAM read has every
// DWORD available (at most 16 reported at a time, the FIFO depth).
#pragma once

#include <cstdint>
#include <span>

#include "ecat/esc/esc.hpp"
#include "ecat/lan9252/lan9252_bus.hpp"

namespace rackcat::ecat {

class Lan9252Model final : public Lan9252Bus {
 public:
  explicit Lan9252Model(Esc& esc) : esc_(esc) {}

  void read(uint16_t address, std::span<uint8_t> data) override;
  void write(uint16_t address, std::span<const uint8_t> data) override;
  bool irq() const override;

 private:
  struct Pram {
    uint16_t address = 0;  // next process-RAM byte
    uint16_t left = 0;     // bytes still to move
    bool busy = false;
  };
  uint32_t read_register(uint16_t address);
  void write_register(uint16_t address, uint32_t value);
  uint32_t fifo_pop();
  void fifo_push(uint32_t value);
  static uint32_t pram_status(const Pram& p);

  Esc& esc_;
  uint32_t csr_data_ = 0;
  uint32_t csr_cmd_ = 0;
  uint32_t int_en_ = 0;
  uint32_t irq_cfg_ = 0;
  uint32_t read_addr_len_ = 0;
  uint32_t write_addr_len_ = 0;
  Pram read_;
  Pram write_;
};

}  // namespace rackcat::ecat
