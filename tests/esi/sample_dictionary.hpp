// A small hand-built object dictionary with the objects the SII and ESI are derived from
// (0x1008, 0x1018, mapping objects, 0x1C12/0x1C13) plus an enum, a packed record with a
// padding gap and per-state access, so the esi tests do not depend on the rack's dictionary.
#pragma once

#include "coe/object_dictionary.hpp"
#include "esi/describe_dictionary.hpp"

namespace rackcat::esi::testing {

inline constexpr uint32_t kVendor = 0x00000ABC;
inline constexpr uint32_t kProduct = 0x00464E01;
inline constexpr uint32_t kRevision = 0x00010009;
inline constexpr uint32_t kSerial = 0x00000042;

coe::ObjectDictionary sample_dictionary();
DeviceTexts sample_texts();

}  // namespace rackcat::esi::testing
