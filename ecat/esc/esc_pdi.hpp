// The emulated ESC's PDI as a PdiPort: what the firmware (ecat/slave) is handed when it runs
// behind the chip model, as it would be handed an SPI or parallel-bus driver on a board.
#pragma once

#include "ecat/esc/esc.hpp"
#include "ecat/pdi_port.hpp"

namespace rackcat::ecat {

class EscPdi final : public PdiPort {
 public:
  explicit EscPdi(Esc& esc) : esc_(esc) {}

  void read(uint16_t address, std::span<uint8_t> dst) override {
    esc_.pdi_read(address, dst.data(), static_cast<uint16_t>(dst.size()));
  }
  void write(uint16_t address, std::span<const uint8_t> src) override {
    esc_.pdi_write(address, src.data(), static_cast<uint16_t>(src.size()));
  }
  void read_buffer(uint8_t sm, uint16_t address, std::span<uint8_t> dst) override {
    esc_.pdi_read_buffer(sm, address, dst.data(), static_cast<uint16_t>(dst.size()));
  }
  void write_buffer(uint8_t sm, uint16_t address, std::span<const uint8_t> src) override {
    esc_.pdi_write_buffer(sm, address, src.data(), static_cast<uint16_t>(src.size()));
  }
  bool irq() const override { return esc_.pdi_irq(); }

 private:
  Esc& esc_;
};

}  // namespace rackcat::ecat
