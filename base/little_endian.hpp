// Explicit little-endian loads and stores, the one helper every layer uses. EtherCAT is
// little-endian on the wire, in the ESC address space (ETG.1000.4 §5.2) and in CoE object
// data (ETG.1000.6 §5.6.2.1.4); we never cast over packed structs.
#pragma once

#include <cstddef>
#include <cstdint>

namespace rackcat::le {

inline uint16_t get16(const uint8_t* p) {
  return static_cast<uint16_t>(p[0] | (p[1] << 8));
}
inline uint32_t get32(const uint8_t* p) {
  return static_cast<uint32_t>(p[0]) | (static_cast<uint32_t>(p[1]) << 8) |
         (static_cast<uint32_t>(p[2]) << 16) | (static_cast<uint32_t>(p[3]) << 24);
}
inline uint64_t get64(const uint8_t* p) {
  return static_cast<uint64_t>(get32(p)) | (static_cast<uint64_t>(get32(p + 4)) << 32);
}
inline void put16(uint8_t* p, uint16_t v) {
  p[0] = static_cast<uint8_t>(v);
  p[1] = static_cast<uint8_t>(v >> 8);
}
inline void put32(uint8_t* p, uint32_t v) {
  put16(p, static_cast<uint16_t>(v));
  put16(p + 2, static_cast<uint16_t>(v >> 16));
}
inline void put64(uint8_t* p, uint64_t v) {
  put32(p, static_cast<uint32_t>(v));
  put32(p + 4, static_cast<uint32_t>(v >> 32));
}
// The first `n` bytes (at most 8 count) as an unsigned number.
inline uint64_t get(const uint8_t* p, size_t n) {
  uint64_t v = 0;
  for (size_t i = 0; i < n && i < 8; ++i) {
    v |= static_cast<uint64_t>(p[i]) << (8 * i);
  }
  return v;
}
// Stores `v` in `n` bytes; bytes beyond the eighth are 0.
inline void put(uint8_t* p, size_t n, uint64_t v) {
  for (size_t i = 0; i < n; ++i) {
    p[i] = i < 8 ? static_cast<uint8_t>(v >> (8 * i)) : 0;
  }
}

}  // namespace rackcat::le
