// Checks an SDO write or read must pass before it touches an object image: per-state access
// (ETG.1000.6 §5.6.3.6.2 ObjectAccess), value range (min/max, enum values, bit width, paired
// limits) and the entry's numeric type range. Shared by single-entry and complete access.
#pragma once

#include <cstdint>
#include <span>

#include "coe/abort_code.hpp"
#include "coe/access.hpp"
#include "coe/object_dictionary.hpp"

namespace rackcat::coe {

// 0x08000022 if readable in another state, 0x06010001 if never readable.
AbortCode check_read_access(uint16_t access_bits, EsmState state);
// 0x08000022 if writable in another state, 0x06010002 if never writable.
AbortCode check_write_access(uint16_t access_bits, EsmState state);

// `value` is the entry's new value, byte_length() bytes, little-endian, a bit entry
// right-aligned. `image` is the object image the pair checks read their sibling from (the
// current image, or the candidate image of a complete access).
AbortCode check_value(const ObjectDictionary& od, const Object& obj, const Entry& entry,
                      std::span<const uint8_t> value, std::span<const uint8_t> image);

// True for the types the min/max checks and SDO Information min/max values apply to:
// BOOLEAN, BITn, INTEGERn, UNSIGNEDn and device enumerations.
bool is_integer_entry(const Entry& entry);
// The entry's effective range: its own min/max if set, else its type's range (a 64-bit
// unsigned maximum is reported as its bit pattern).
int64_t effective_min(const Entry& entry);
int64_t effective_max(const Entry& entry);

}  // namespace rackcat::coe
