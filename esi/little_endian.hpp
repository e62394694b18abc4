// Explicit little-endian reads and writes for the SII image. EtherCAT is little-endian on the
// wire and in the EEPROM (ETG.1000.4 §5.2, ETG.2010 §2); we never cast over packed structs.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace rackcat::esi::le {

inline void put8(std::vector<uint8_t>& out, uint8_t v) {
  out.push_back(v);
}
inline void put16(std::vector<uint8_t>& out, uint16_t v) {
  out.push_back(static_cast<uint8_t>(v));
  out.push_back(static_cast<uint8_t>(v >> 8));
}
inline void put32(std::vector<uint8_t>& out, uint32_t v) {
  put16(out, static_cast<uint16_t>(v));
  put16(out, static_cast<uint16_t>(v >> 16));
}

inline void store16(std::span<uint8_t> at, size_t offset, uint16_t v) {
  at[offset] = static_cast<uint8_t>(v);
  at[offset + 1] = static_cast<uint8_t>(v >> 8);
}
inline void store32(std::span<uint8_t> at, size_t offset, uint32_t v) {
  store16(at, offset, static_cast<uint16_t>(v));
  store16(at, offset + 2, static_cast<uint16_t>(v >> 16));
}

inline uint16_t get16(std::span<const uint8_t> at, size_t offset) {
  return static_cast<uint16_t>(at[offset] | (at[offset + 1] << 8));
}
inline uint32_t get32(std::span<const uint8_t> at, size_t offset) {
  return static_cast<uint32_t>(get16(at, offset)) |
         (static_cast<uint32_t>(get16(at, offset + 2)) << 16);
}

}  // namespace rackcat::esi::le
