// Bit-granular copies shared by the object images, complete access and the
// process image. EtherCAT numbers bits LSB-first inside each byte and bytes in ascending
// order (ETG.1000.4 §5.2; ETG.1000.6 §5.6.2.1.4 for complete access), so bit n of a buffer is
// bit (n % 8) of byte n / 8.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>

#include "base/little_endian.hpp"

namespace rackcat::coe {

// Copies `nbits` bits from src (starting at bit src_bit) to dst (starting at bit dst_bit);
// bits of dst outside the range keep their value. Byte-aligned runs become one memcpy.
inline void copy_bits(uint8_t* dst, size_t dst_bit, const uint8_t* src, size_t src_bit,
                      size_t nbits) {
  if (nbits == 0) {
    return;
  }
  if ((dst_bit % 8) == 0 && (src_bit % 8) == 0) {
    const size_t whole = nbits / 8;
    std::memcpy(dst + dst_bit / 8, src + src_bit / 8, whole);
    const size_t rest = nbits % 8;
    if (rest) {
      const uint8_t mask = static_cast<uint8_t>((1u << rest) - 1u);
      uint8_t& d = dst[dst_bit / 8 + whole];
      d = static_cast<uint8_t>((d & ~mask) | (src[src_bit / 8 + whole] & mask));
    }
    return;
  }
  for (size_t i = 0; i < nbits; ++i) {
    const size_t s = src_bit + i;
    const size_t d = dst_bit + i;
    const uint8_t bit = static_cast<uint8_t>((src[s / 8] >> (s % 8)) & 1u);
    dst[d / 8] = static_cast<uint8_t>((dst[d / 8] & ~(1u << (d % 8))) | (bit << (d % 8)));
  }
}

}  // namespace rackcat::coe
