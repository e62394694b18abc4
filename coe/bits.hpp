// Little-endian and bit-granular copies shared by the object images, complete access and the
// process image. EtherCAT numbers bits LSB-first inside each byte and bytes in ascending
// order (ETG.1000.4 §5.2; ETG.1000.6 §5.6.2.1.4 for complete access), so bit n of a buffer is
// bit (n % 8) of byte n / 8.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>

namespace rackcat::coe {

inline uint16_t get_le16(const uint8_t* p) {
  return static_cast<uint16_t>(p[0] | (p[1] << 8));
}
inline uint32_t get_le32(const uint8_t* p) {
  return static_cast<uint32_t>(p[0]) | (static_cast<uint32_t>(p[1]) << 8) |
         (static_cast<uint32_t>(p[2]) << 16) | (static_cast<uint32_t>(p[3]) << 24);
}
inline void put_le16(uint8_t* p, uint16_t v) {
  p[0] = static_cast<uint8_t>(v);
  p[1] = static_cast<uint8_t>(v >> 8);
}
inline void put_le32(uint8_t* p, uint32_t v) {
  for (int i = 0; i < 4; ++i) {
    p[i] = static_cast<uint8_t>(v >> (8 * i));
  }
}
// Reads up to 8 little-endian bytes.
inline uint64_t get_le(const uint8_t* p, size_t n) {
  uint64_t v = 0;
  for (size_t i = 0; i < n && i < 8; ++i) {
    v |= static_cast<uint64_t>(p[i]) << (8 * i);
  }
  return v;
}
inline void put_le(uint8_t* p, size_t n, uint64_t v) {
  for (size_t i = 0; i < n; ++i) {
    p[i] = i < 8 ? static_cast<uint8_t>(v >> (8 * i)) : 0;
  }
}

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
