// SDO requests and replies as bytes, framed the way a master writes them into SM0 (ETG.1000.4
// §5.6 mailbox header, ETG.1000.6 §5.6.1 CoE header, §5.6.2 SDO command specifiers). Pure byte
// helpers, shared by the coe, mdp and modules tests.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace rackcat::testing {

using Bytes = std::vector<uint8_t>;

// Mailbox header + CoE header + body, as a master writes it into SM0.
inline Bytes coe_message(uint8_t counter, uint8_t service, const Bytes& body) {
  const uint16_t len = static_cast<uint16_t>(2 + body.size());
  Bytes m(8 + body.size());
  m[0] = static_cast<uint8_t>(len);
  m[1] = static_cast<uint8_t>(len >> 8);
  m[5] = static_cast<uint8_t>(0x03 | (counter << 4));  // CoE, counter in bits 4-6
  m[7] = static_cast<uint8_t>(service << 4);           // CoE service in bits 12-15
  std::copy(body.begin(), body.end(), m.begin() + 8);
  return m;
}

// CoE header 0x3000 (SDO response) / 0x2000 (SDO request, used by aborts) little-endian.
inline Bytes abort_payload(uint16_t index, uint8_t sub, uint32_t code) {
  return {0x00,
          0x20,
          0x80,
          static_cast<uint8_t>(index),
          static_cast<uint8_t>(index >> 8),
          sub,
          static_cast<uint8_t>(code),
          static_cast<uint8_t>(code >> 8),
          static_cast<uint8_t>(code >> 16),
          static_cast<uint8_t>(code >> 24)};
}

// Upload / download request bodies (ETG.1000.6 Tables 35-40).
inline Bytes upload_req(uint16_t index, uint8_t sub, bool ca = false) {
  return {static_cast<uint8_t>(ca ? 0x50 : 0x40),
          static_cast<uint8_t>(index),
          static_cast<uint8_t>(index >> 8),
          sub,
          0,
          0,
          0,
          0};
}
inline Bytes download_expedited(uint16_t index, uint8_t sub, uint32_t value, size_t n,
                                bool ca = false) {
  return {static_cast<uint8_t>(0x23 | ((4 - n) << 2) | (ca ? 0x10 : 0)),
          static_cast<uint8_t>(index),
          static_cast<uint8_t>(index >> 8),
          sub,
          static_cast<uint8_t>(value),
          static_cast<uint8_t>(value >> 8),
          static_cast<uint8_t>(value >> 16),
          static_cast<uint8_t>(value >> 24)};
}
inline Bytes download_normal(uint16_t index, uint8_t sub, const Bytes& data, bool ca = false,
                             size_t announced = SIZE_MAX) {
  const uint32_t size = static_cast<uint32_t>(announced == SIZE_MAX ? data.size() : announced);
  Bytes b(8 + data.size());
  b[0] = static_cast<uint8_t>(0x21 | (ca ? 0x10 : 0));  // normal, size indicated
  b[1] = static_cast<uint8_t>(index);
  b[2] = static_cast<uint8_t>(index >> 8);
  b[3] = sub;
  for (int i = 0; i < 4; ++i) b[4 + i] = static_cast<uint8_t>(size >> (8 * i));
  std::copy(data.begin(), data.end(), b.begin() + 8);
  return b;
}
inline Bytes download_ok(uint16_t index, uint8_t sub, bool ca = false) {
  return {0x00,
          0x30,
          static_cast<uint8_t>(ca ? 0x70 : 0x60),
          static_cast<uint8_t>(index),
          static_cast<uint8_t>(index >> 8),
          sub,
          0,
          0,
          0,
          0};
}

}  // namespace rackcat::testing
