// Register and ESC write protection (Beckhoff ESC documentation section I §17.3, registers
// 0x0020/0x0021 and 0x0030/0x0031). With register write protection on (0x0021 bit 0), writes
// to 0x0000-0x0F7F other than 0x0020/0x0030 are discarded unless 0x0020 bit 0 was written
// earlier in the same frame; with ESC write protection on (0x0031 bit 0) the same holds for
// every address, with 0x0030 as the enable. A datagram whose every byte was discarded gets no
// working counter (the datasheet only says the write is discarded; no WKC lets a master see it).
#include <algorithm>
#include <cstring>

#include "ecat/esc/esc.hpp"
#include "ecat/registers.hpp"

namespace rackcat::ecat {

namespace {
constexpr uint16_t kUserRam = 0x0F80;
}

void Esc::derive_write_protection() {
  protection_ =
      static_cast<uint8_t>(((mem_[reg::kWriteProtection] & 0x01) ? kRegisterProtection : 0) |
                           ((mem_[reg::kEscWriteProtection] & 0x01) ? kEscProtection : 0));
}

bool Esc::write_allowed(uint32_t address) const {
  if (address == reg::kWriteEnable || address == reg::kEscWriteEnable) return true;
  if ((mem_[reg::kEscWriteProtection] & 0x01) && !esc_write_enabled_) return false;
  if (address < kUserRam && (mem_[reg::kWriteProtection] & 0x01) && !register_write_enabled_) {
    return false;
  }
  return true;
}

void Esc::write_enables_written(uint16_t address, const uint8_t* src, uint16_t len) {
  const uint32_t end = static_cast<uint32_t>(address) + len;
  if (address <= reg::kWriteEnable && reg::kWriteEnable < end &&
      (src[reg::kWriteEnable - address] & 0x01)) {
    register_write_enabled_ = true;
  }
  if (address <= reg::kEscWriteEnable && reg::kEscWriteEnable < end &&
      (src[reg::kEscWriteEnable - address] & 0x01)) {
    esc_write_enabled_ = true;
  }
}

bool Esc::protected_write(uint16_t address, const uint8_t* src, uint16_t len) {
  // Byte runs that may be written, processed in order: an enable byte ends its run, so the
  // bytes after it see the released protection.
  bool any = false;
  uint32_t i = 0;
  while (i < len) {
    const uint32_t a = address + i;
    if (!write_allowed(a)) {
      ++i;
      continue;
    }
    uint32_t j = i + 1;
    const bool registers = a < reg::kProcessRam;
    while (j < len && write_allowed(address + j) &&
           ((address + j) < reg::kProcessRam) == registers &&
           address + j - 1 != reg::kWriteEnable && address + j - 1 != reg::kEscWriteEnable) {
      ++j;
    }
    const auto run_address = static_cast<uint16_t>(a);
    const auto run_len = static_cast<uint16_t>(j - i);
    if (registers) {
      write_registers(run_address, src + i, run_len);
      after_register_write(run_address, src + i, run_len);
    } else {
      std::memcpy(&mem_[run_address], src + i, run_len);
      sm_after_write(run_address, run_len);
    }
    any = true;
    i = j;
  }
  return any;
}

}  // namespace rackcat::ecat
