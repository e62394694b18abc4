// CANopen emergency object (CiA 301 §7.2.7): COB-ID 0x080 + node-ID, 8 bytes = error code
// (UNSIGNED16, little-endian), error register (0x1001), 5 bytes manufacturer-specific. The
// same three fields as a CoE Emergency (ETG.1000.6 §5.6.4), so coe::Emergency carries both.
#pragma once

#include <optional>

#include "coe/bits.hpp"
#include "coe/emergency_queue.hpp"
#include "modules/canopen/frame.hpp"

namespace rackcat::modules::canopen {

inline CanFrame emcy_frame(uint8_t node, const coe::Emergency& e) {
  CanFrame f;
  f.id = cob::kEmcy + node;
  f.len = 8;
  le::put16(f.data.data(), e.error_code);
  f.data[2] = e.error_register;
  for (size_t i = 0; i < e.data.size(); ++i) {
    f.data[3 + i] = e.data[i];
  }
  return f;
}

// The emergency in an EMCY frame; nullopt for other frames, SYNC (node-ID 0) and frames
// shorter than the 8 bytes CiA 301 prescribes.
inline std::optional<coe::Emergency> decode_emcy(const CanFrame& f) {
  if (cob::function(f.id) != cob::kEmcy || cob::node(f.id) == 0 || f.len != 8) {
    return std::nullopt;
  }
  coe::Emergency e;
  e.error_code = le::get16(f.data.data());
  e.error_register = f.data[2];
  for (size_t i = 0; i < e.data.size(); ++i) {
    e.data[i] = f.data[3 + i];
  }
  return e;
}

}  // namespace rackcat::modules::canopen
