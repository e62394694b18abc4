#include "esi/sii_crc.hpp"

namespace rackcat::esi {

uint8_t sii_crc8(std::span<const uint8_t> bytes) {
  // MSB-first shift register, one bit at a time: 14 bytes once per image, speed is irrelevant.
  uint8_t crc = 0xFF;
  for (uint8_t byte : bytes) {
    crc ^= byte;
    for (int bit = 0; bit < 8; ++bit) {
      crc = (crc & 0x80) ? static_cast<uint8_t>((crc << 1) ^ 0x07) : static_cast<uint8_t>(crc << 1);
    }
  }
  return crc;
}

}  // namespace rackcat::esi
