// One FMMU's 16 configuration bytes as a master writes them at 0x0600 + 16n (ETG.1000.4 §6.6
// "FMMU", register layout): logical start address (UINT32), length in bytes (UINT16), logical
// start bit, logical stop bit, physical start address (UINT16), physical start bit, type
// (1 read, 2 write, 3 read/write), activate (bit 0), 3 reserved bytes. Little-endian.
#pragma once

#include <cstdint>
#include <vector>

namespace rackcat::testing {

inline std::vector<uint8_t> fmmu_entry(uint32_t logical, uint16_t length, uint8_t start_bit,
                                       uint8_t stop_bit, uint16_t physical, uint8_t physical_bit,
                                       uint8_t type, uint8_t enable = 0x01) {
  return {static_cast<uint8_t>(logical),
          static_cast<uint8_t>(logical >> 8),
          static_cast<uint8_t>(logical >> 16),
          static_cast<uint8_t>(logical >> 24),
          static_cast<uint8_t>(length),
          static_cast<uint8_t>(length >> 8),
          start_bit,
          stop_bit,
          static_cast<uint8_t>(physical),
          static_cast<uint8_t>(physical >> 8),
          physical_bit,
          type,
          enable,
          0,
          0,
          0};
}

}  // namespace rackcat::testing
