// The checksum of the SII ESC configuration area (ETG.2010 §2.1, ETG.1000.6 §5.4 Table 2):
// word 7's low byte is the CRC-8 of bytes 0..13 (words 0..6) with polynomial x^8+x^2+x+1
// (0x07), initial value 0xFF, no reflection and no final XOR. The ESC refuses to load words
// 0..6 into its registers when it does not match.
#pragma once

#include <cstdint>
#include <span>

namespace rackcat::esi {

uint8_t sii_crc8(std::span<const uint8_t> bytes);

}  // namespace rackcat::esi
