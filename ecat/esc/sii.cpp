// SII EEPROM interface 0x0500-0x050F (ETG.1000.4 §6.4.5, ESC datasheet 0x0500-0x050F) and the
// EEPROM load of the ESC configuration area (words 0-7) at power-up and on reload. The
// interface belongs to the master unless it offered it to the PDI (0x0500 bit 0) and the PDI
// took it (0x0501 bit 0); its owner alone writes 0x0502-0x050F (ESC datasheet 0x0502).
#include <algorithm>
#include <cstring>

#include "base/little_endian.hpp"
#include "ecat/esc/esc.hpp"
#include "ecat/registers.hpp"

namespace rackcat::ecat {

namespace {

// 0x0502-0x0503 control/status bits.
constexpr uint16_t kWriteEnable = 0x0001;
constexpr uint16_t kReadSize8 = 0x0040;         // 1: 8 bytes per read, 0: 4 bytes
constexpr uint16_t kTwoAddressBytes = 0x0080;   // EEPROM larger than 16 Kbit
constexpr uint16_t kChecksumError = 0x0800;     // CRC of words 0-6 wrong
constexpr uint16_t kNotLoaded = 0x1000;         // configuration area not loaded
constexpr uint16_t kNack = 0x2000;              // missing acknowledge or invalid command
constexpr uint16_t kWriteEnableError = 0x4000;  // write command without write enable
// Commands, bits 10:8 (the 3-bit value written to 0x0503).
constexpr uint8_t kCmdIdle = 0x0;
constexpr uint8_t kCmdRead = 0x1;
constexpr uint8_t kCmdWrite = 0x2;
constexpr uint8_t kCmdReload = 0x4;

// ETG.1000.6 / ETG.2010: CRC-8 over words 0-6, polynomial x^8 + x^2 + x + 1, initial 0xFF.
uint8_t crc8(const uint8_t* p, size_t n) {
  uint8_t crc = 0xFF;
  for (size_t i = 0; i < n; ++i) {
    crc ^= p[i];
    for (int b = 0; b < 8; ++b)
      crc = static_cast<uint8_t>((crc & 0x80) ? (crc << 1) ^ 0x07 : crc << 1);
  }
  return crc;
}

}  // namespace

bool Esc::sii_assigned_to_pdi() const {
  return (mem_[reg::kSiiConfig] & 0x01) != 0 && (mem_[reg::kSiiPdiAccess] & 0x01) != 0;
}

// PDI-writable bits of 0x0501-0x050F. Control/command 0x0502-0x0503 are actions
// (pdi_registers_written runs the command), not stored.
uint8_t Esc::sii_pdi_write_mask(uint16_t address, bool sii_owned) const {
  if (address == reg::kSiiPdiAccess) return (mem_[reg::kSiiConfig] & 0x01) != 0 ? 0x01 : 0x00;
  if (!sii_owned || address < reg::kSiiAddress) return 0x00;
  return 0xFF;  // address 0x0504-0x0507, data 0x0508-0x050F
}

void Esc::sii_load_image() {
  const std::span<const uint8_t> image = eeprom_.image();
  // Word 0x3E holds the EEPROM size in Kbit minus 1 (ETG.2010 Table 2); the device may hand
  // us a shorter image: the rest of the chip reads as erased (0xFF).
  size_t size = image.size();
  if (image.size() >= 0x80) {
    const size_t declared = (static_cast<size_t>(le::get16(&image[0x7C])) + 1) * 128;
    size = std::max(size, std::min<size_t>(declared, 0x20000));
  }
  sii_.assign(size, 0xFF);
  std::copy(image.begin(), image.end(), sii_.begin());
}

void Esc::sii_reload_config_area() {
  uint16_t status = options_.sii_read_bytes == 8 ? kReadSize8 : 0;
  if (sii_.size() > 2048) status |= kTwoAddressBytes;
  if (sii_.size() < 16 || crc8(sii_.data(), 14) != sii_[14]) {
    // The ESC refuses a missing configuration area or one with a bad checksum and leaves the
    // PDI off.
    status |= kNotLoaded | kChecksumError;
  } else {
    std::memcpy(&mem_[reg::kPdiControl], &sii_[0], 2);     // word 0: PDI control, ESC config
    std::memcpy(&mem_[reg::kPdiConfig], &sii_[2], 2);      // word 1: PDI configuration
    std::memcpy(&mem_[reg::kDcPulseLength], &sii_[4], 2);  // word 2: SYNC pulse length
    std::memcpy(&mem_[reg::kPdiConfigExt], &sii_[6], 2);   // word 3: extended PDI config
    std::memcpy(&mem_[reg::kStationAlias], &sii_[8], 2);   // word 4: configured alias
  }
  le::put16(&mem_[reg::kSiiControl], status);
}

void Esc::sii_command(uint8_t control_lo, uint8_t command, bool control_lo_written) {
  uint16_t status = le::get16(&mem_[reg::kSiiControl]);
  // A new command clears the error bits of the previous one; commands complete at once, so
  // busy (bit 15) is never seen set and the command field reads back idle.
  status &= static_cast<uint16_t>(~(kNack | kWriteEnableError | 0x0700 | kWriteEnable));
  const uint64_t byte_address = static_cast<uint64_t>(le::get32(&mem_[reg::kSiiAddress])) * 2;
  switch (command) {
    case kCmdIdle:
      break;
    case kCmdRead: {
      if (byte_address >= sii_.size()) {
        status |= kNack;  // no EEPROM cell answers at that address
        break;
      }
      for (uint8_t i = 0; i < options_.sii_read_bytes; ++i) {
        const uint64_t a = byte_address + i;
        mem_[reg::kSiiData + i] = a < sii_.size() ? sii_[a] : 0xFF;
      }
      break;
    }
    case kCmdWrite: {
      if (!control_lo_written || (control_lo & kWriteEnable) == 0) {
        status |= kWriteEnableError;
        break;
      }
      if (byte_address + 1 >= sii_.size()) {
        status |= kNack;
        break;
      }
      sii_[byte_address] = mem_[reg::kSiiData];
      sii_[byte_address + 1] = mem_[reg::kSiiData + 1];
      eeprom_.on_write(static_cast<uint16_t>(byte_address / 2),
                       std::span<const uint8_t>(&sii_[byte_address], 2));
      break;
    }
    case kCmdReload: {
      sii_reload_config_area();
      status = le::get16(&mem_[reg::kSiiControl]);
      set_port1_link(port1_link_);  // DL status bit 0 follows the load result
      break;
    }
    default:
      status |= kNack;  // invalid command (ESC datasheet 0x0502: only 000, 001, 010, 100)
      break;
  }
  le::put16(&mem_[reg::kSiiControl], status);
}

}  // namespace rackcat::ecat
