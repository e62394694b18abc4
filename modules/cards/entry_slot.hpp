// A cached, byte-aligned 8/16-bit entry of an object image, so the cyclic path writes the
// value directly (little-endian, ETG.1000.6 §5.6.2) instead of looking the entry up each
// cycle. Entries that are not byte-aligned fall back to Object::set_u.
#pragma once

#include <cstdint>

#include "coe/object_dictionary.hpp"

namespace rackcat::modules {

class EntrySlot {
 public:
  EntrySlot() = default;
  EntrySlot(coe::Object& o, uint8_t sub) : obj_(&o), sub_(sub) {
    const coe::Entry* e = o.entry(sub);
    if (e != nullptr && e->bit_offset % 8 == 0 && (e->bit_length == 8 || e->bit_length == 16)) {
      auto b = o.bytes(sub);
      if (b.size() * 8 >= e->bit_length) {
        p_ = b.data();
        bytes_ = static_cast<uint8_t>(e->bit_length / 8);
      }
    }
  }
  void set(uint32_t v) {
    if (p_ != nullptr) {
      p_[0] = static_cast<uint8_t>(v);
      if (bytes_ == 2) p_[1] = static_cast<uint8_t>(v >> 8);
    } else if (obj_ != nullptr) {
      obj_->set_u(sub_, v);
    }
  }

 private:
  coe::Object* obj_ = nullptr;
  uint8_t sub_ = 0;
  uint8_t* p_ = nullptr;
  uint8_t bytes_ = 0;
};

}  // namespace rackcat::modules
