#include "mdp/process_image.hpp"

#include <cstring>

#include "coe/bits.hpp"

namespace rackcat::mdp {

ProcessImage::ProcessImage(coe::ObjectDictionary& od, uint16_t assign_index)
    : od_(od), assign_index_(assign_index) {
  size_t capacity = 0;
  const uint16_t lo = assign_index == 0x1C12 ? 0x1600 : 0x1A00;
  od.for_each([&](const coe::Object& o) {
    if (o.index() >= lo && o.index() < lo + 0x200) capacity += o.entries().size();
  });
  copies_.reserve(capacity);
  compile();
}

void ProcessImage::compile() {
  copies_.clear();
  uint32_t pd_bit = 0;
  const coe::Object* assign = od_.find(assign_index_);
  const uint8_t pdos = assign ? assign->sub0() : 0;
  for (uint8_t i = 1; i <= pdos; ++i) {
    const coe::Object* pdo = od_.find(static_cast<uint16_t>(assign->get_u(i)));
    if (!pdo) continue;
    for (uint8_t s = 1; s <= pdo->sub0(); ++s) {
      const uint32_t map = static_cast<uint32_t>(pdo->get_u(s));
      const uint16_t index = static_cast<uint16_t>(map >> 16);
      const uint8_t sub = static_cast<uint8_t>(map >> 8);
      const uint32_t bits = map & 0xFF;
      coe::Object* obj = index ? od_.find(index) : nullptr;
      const coe::Entry* e = obj ? obj->entry(sub) : nullptr;
      if (e && copies_.size() < copies_.capacity()) {
        const uint32_t object_bit = e->bit_offset;
        Copy* prev = copies_.empty() ? nullptr : &copies_.back();
        // Neighbouring entries of one object that are neighbours in the PDO too: one copy.
        if (prev && prev->object == obj && prev->object_bit + prev->bits == object_bit &&
            prev->pd_bit + prev->bits == pd_bit) {
          prev->bits += bits;
        } else {
          copies_.push_back({obj, object_bit, pd_bit, bits});
        }
      }
      pd_bit += bits;
    }
  }
  bytes_ = static_cast<uint16_t>((pd_bit + 7) / 8);
}

void ProcessImage::to_objects(std::span<const uint8_t> pd) const {
  const size_t limit = pd.size() * 8;
  for (const Copy& c : copies_) {
    if (c.pd_bit + c.bits > limit) break;
    coe::copy_bits(c.object->image().data(), c.object_bit, pd.data(), c.pd_bit, c.bits);
  }
}

void ProcessImage::from_objects(std::span<uint8_t> pd) const {
  // Padding bits read as 0.
  std::memset(pd.data(), 0, pd.size());
  const size_t limit = pd.size() * 8;
  for (const Copy& c : copies_) {
    if (c.pd_bit + c.bits > limit) break;
    coe::copy_bits(pd.data(), c.pd_bit, c.object->image().data(), c.object_bit, c.bits);
  }
}

}  // namespace rackcat::mdp
