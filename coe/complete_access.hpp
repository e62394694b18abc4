// Complete access layout helpers (ETG.1000.6 §5.6.2.1.4 / §5.6.2.2.4): the transferred data
// is the object image from subindex 0 (16 bits: value + 8 bits padding) or from subindex 1
// (bit 16 on), up to the last entry in use (subindex 0's value); gap bits are 0.
#pragma once

#include <cstddef>
#include <cstdint>

#include "coe/object_dictionary.hpp"

namespace rackcat::coe {

// First image bit of a complete access starting at `subindex` (0 or 1).
constexpr size_t ca_begin_bit(uint8_t subindex) {
  return subindex == 0 ? 0 : 16;
}
// Last subindex a complete access covers: subindex 0's value, at most the highest entry.
uint8_t ca_last_subindex(const Object& obj);
// Bytes a complete access from `subindex` through `last` transfers.
size_t ca_bytes(const Object& obj, uint8_t subindex, uint8_t last);
// Copies entries `first`..`last` (padding excluded, subindex 0 as 8 bits) from the image to
// `out` (zeroed first, ca_bytes long), so gaps read as 0.
void ca_extract(const Object& obj, uint8_t first, uint8_t last, uint8_t* out);

}  // namespace rackcat::coe
