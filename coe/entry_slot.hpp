// A cached entry of an object image: the byte address of a byte-aligned 8/16/32/64-bit entry,
// found once when the object exists, so the cyclic path reads and writes the value directly
// (little-endian, ETG.1000.6 §5.6.2) instead of looking the entry up each cycle (issue 16:
// "each PDO entry's byte/bit slot computed when the mapping is fixed"). Entries that are not
// byte-aligned (BIT1..BIT7, packed records) fall back to Object::get_u/set_u.
//
// The slot points into the object's image: the dictionary keeps objects (and images) in place
// for the device's lifetime (object_dictionary.hpp), as the process image's copies do.
#pragma once

#include <bit>
#include <cstdint>
#include <cstring>

#include "base/little_endian.hpp"
#include "coe/object_dictionary.hpp"

namespace rackcat::coe {

class EntrySlot {
 public:
  EntrySlot() = default;
  EntrySlot(Object& o, uint8_t sub) : obj_(&o), sub_(sub) {
    const Entry* e = o.entry(sub);
    if (e != nullptr && e->bit_offset % 8 == 0 &&
        (e->bit_length == 8 || e->bit_length == 16 || e->bit_length == 32 || e->bit_length == 64)) {
      auto b = o.bytes(sub);
      if (b.size() * 8 >= e->bit_length) {
        p_ = b.data();
        bytes_ = static_cast<uint8_t>(e->bit_length / 8);
      }
    }
  }
  void set(uint64_t v) {
    switch (p_ != nullptr ? bytes_ : 0) {
      case 1:
        p_[0] = static_cast<uint8_t>(v);
        return;
      case 2:
        store<uint16_t>(v);
        return;
      case 4:
        store<uint32_t>(v);
        return;
      case 8:
        store<uint64_t>(v);
        return;
      default:
        if (obj_ != nullptr) obj_->set_u(sub_, v);
    }
  }
  uint64_t get() const {
    switch (p_ != nullptr ? bytes_ : 0) {
      case 1:
        return p_[0];
      case 2:
        return load<uint16_t>();
      case 4:
        return load<uint32_t>();
      case 8:
        return load<uint64_t>();
      default:
        return obj_ != nullptr ? obj_->get_u(sub_) : 0;
    }
  }
  explicit operator bool() const { return obj_ != nullptr; }

 private:
  // One load/store of the whole entry on a little-endian host (the object image's byte order),
  // byte by byte elsewhere; the image may hold it at any byte address.
  template <class T>
  void store(uint64_t v) {
    if constexpr (std::endian::native == std::endian::little) {
      const auto t = static_cast<T>(v);
      std::memcpy(p_, &t, sizeof t);
    } else {
      le::put(p_, sizeof(T), v);
    }
  }
  template <class T>
  uint64_t load() const {
    if constexpr (std::endian::native == std::endian::little) {
      T t = 0;
      std::memcpy(&t, p_, sizeof t);
      return t;
    } else {
      return le::get(p_, sizeof(T));
    }
  }

  // 24 bytes rather than 32: drivers keep several slots among their per-cycle fields.
  uint8_t* p_ = nullptr;
  Object* obj_ = nullptr;
  uint8_t sub_ = 0;
  uint8_t bytes_ = 0;
};

}  // namespace rackcat::coe
