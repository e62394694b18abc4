// The LAN9252 host-bus protocol in front of the emulated ESC (LAN9252 datasheet Table 5-1,
// "EtherCAT CSR and process data RAM access"). See lan9252_model.hpp.
#include "ecat/esc/lan9252_model.hpp"

#include <algorithm>

#include "base/little_endian.hpp"

namespace rackcat::ecat {

namespace {
constexpr uint32_t kIdRevValue = 0x92520001;  // chip ID 0x9252, revision 1
}  // namespace

bool Lan9252Model::irq() const {
  // INT_STS bit 0 (EtherCAT interrupt) gated by INT_EN bit 0 and IRQ_CFG bit 8 (IRQ_EN).
  return (int_en_ & 1) && (irq_cfg_ & 0x100) && esc_.pdi_irq();
}

uint32_t Lan9252Model::pram_status(const Pram& p) {
  if (!p.busy) return 0;
  const uint32_t dwords = std::min<uint32_t>((p.left + 3u) / 4u, lan9252::kFifoDwords);
  return lan9252::kPramBusy | (dwords << 8) | (dwords != 0 ? lan9252::kPramAvail : 0);
}

uint32_t Lan9252Model::fifo_pop() {
  // One DWORD of the read FIFO: the bytes from the current address up to the next DWORD
  // boundary (the first DWORD starts in the address's lane), read from the ESC through its
  // PDI as the LAN9252's own PDI would.
  uint8_t b[4] = {0, 0, 0, 0};
  if (!read_.busy || read_.left == 0) return 0;
  const size_t lane = read_.address & 3;
  const auto n = static_cast<uint16_t>(std::min<size_t>(4 - lane, read_.left));
  esc_.pdi_read(read_.address, b + lane, n);
  read_.address = static_cast<uint16_t>(read_.address + n);
  read_.left = static_cast<uint16_t>(read_.left - n);
  if (read_.left == 0) read_.busy = false;
  return le::get32(b);
}

void Lan9252Model::fifo_push(uint32_t value) {
  if (!write_.busy || write_.left == 0) return;
  uint8_t b[4];
  le::put32(b, value);
  const size_t lane = write_.address & 3;
  const auto n = static_cast<uint16_t>(std::min<size_t>(4 - lane, write_.left));
  esc_.pdi_write(write_.address, b + lane, n);
  write_.address = static_cast<uint16_t>(write_.address + n);
  write_.left = static_cast<uint16_t>(write_.left - n);
  if (write_.left == 0) write_.busy = false;
}

uint32_t Lan9252Model::read_register(uint16_t address) {
  if (address < lan9252::kPramWriteFifo) return fifo_pop();
  switch (address) {
    case lan9252::kIdRev:
      return kIdRevValue;
    case lan9252::kIrqCfg:
      return irq_cfg_ | (irq() ? 0x1000u : 0u);  // bit 12: IRQ interrupt status
    case lan9252::kIntSts:
      return esc_.pdi_irq() ? 1u : 0u;
    case lan9252::kIntEn:
      return int_en_;
    case lan9252::kByteTest:
      return lan9252::kByteTestValue;
    case lan9252::kHwCfg:
      return lan9252::kHwCfgReady;
    case lan9252::kCsrData:
      return csr_data_;
    case lan9252::kCsrCmd:
      return csr_cmd_;  // completes at once: busy never seen
    case lan9252::kPramReadAddrLen:
      return read_addr_len_;
    case lan9252::kPramReadCmd:
      return pram_status(read_);
    case lan9252::kPramWriteAddrLen:
      return write_addr_len_;
    case lan9252::kPramWriteCmd: {
      // Space for the rest of the transfer, at most the FIFO depth.
      if (!write_.busy) return 0;
      const uint32_t dwords = std::min<uint32_t>((write_.left + 3u) / 4u, lan9252::kFifoDwords);
      return lan9252::kPramBusy | (dwords << 8) | lan9252::kPramAvail;
    }
    default:
      return 0;
  }
}

void Lan9252Model::write_register(uint16_t address, uint32_t value) {
  if (address >= lan9252::kPramWriteFifo && address < lan9252::kPramWriteFifo + 0x20) {
    fifo_push(value);
    return;
  }
  switch (address) {
    case lan9252::kIrqCfg:
      irq_cfg_ = value & 0x0000F111u;
      break;
    case lan9252::kIntEn:
      int_en_ = value;
      break;
    case lan9252::kCsrData:
      csr_data_ = value;
      break;
    case lan9252::kCsrCmd: {
      // busy | read | size (1, 2, 4) | ESC register address: runs at once.
      const auto reg = static_cast<uint16_t>(value & 0xFFFF);
      const auto size = static_cast<uint16_t>((value >> 16) & 0x7);
      if ((value & lan9252::kCsrBusy) && (size == 1 || size == 2 || size == 4) &&
          reg + size <= 0x1000) {
        uint8_t b[4];
        if (value & lan9252::kCsrRead) {
          le::put32(b, 0);
          esc_.pdi_read(reg, b, size);
          csr_data_ = le::get32(b);
        } else {
          le::put32(b, csr_data_);
          esc_.pdi_write(reg, b, size);
        }
      }
      csr_cmd_ = value & ~lan9252::kCsrBusy;
      break;
    }
    case lan9252::kPramReadAddrLen:
      read_addr_len_ = value;
      break;
    case lan9252::kPramReadCmd:
      if (value & lan9252::kPramAbort) read_ = {};
      if (value & lan9252::kPramBusy) {
        read_ = {static_cast<uint16_t>(read_addr_len_ & 0xFFFF),
                 static_cast<uint16_t>(read_addr_len_ >> 16), true};
      }
      break;
    case lan9252::kPramWriteAddrLen:
      write_addr_len_ = value;
      break;
    case lan9252::kPramWriteCmd:
      if (value & lan9252::kPramAbort) write_ = {};
      if (value & lan9252::kPramBusy) {
        write_ = {static_cast<uint16_t>(write_addr_len_ & 0xFFFF),
                  static_cast<uint16_t>(write_addr_len_ >> 16), true};
      }
      break;
    default:
      break;
  }
}

void Lan9252Model::read(uint16_t address, std::span<uint8_t> data) {
  // DWORD registers; a longer read continues at the next DWORD (FIFO addresses alias).
  for (size_t i = 0; i < data.size(); i += 4) {
    uint8_t b[4];
    le::put32(b, read_register(static_cast<uint16_t>(address + i)));
    std::copy_n(b, std::min<size_t>(4, data.size() - i), data.begin() + static_cast<long>(i));
  }
}

void Lan9252Model::write(uint16_t address, std::span<const uint8_t> data) {
  for (size_t i = 0; i < data.size(); i += 4) {
    uint8_t b[4] = {0, 0, 0, 0};
    std::copy_n(data.begin() + static_cast<long>(i), std::min<size_t>(4, data.size() - i), b);
    write_register(static_cast<uint16_t>(address + i), le::get32(b));
  }
}

}  // namespace rackcat::ecat
