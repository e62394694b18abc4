#include "mdp/parameter_set.hpp"

#include <zlib.h>

#include <algorithm>

#include "coe/bits.hpp"

namespace rackcat::mdp {

ParameterSet::ParameterSet(coe::ObjectDictionary& od, const RackConfig& config) {
  auto add = [&](uint16_t index, uint8_t sub) {
    coe::Object* o = od.find(index);
    const coe::Entry* e = o ? o->entry(sub) : nullptr;
    if (!e || e->padding) return;
    const bool raw = e->bit_offset % 8 == 0 && e->bit_length % 8 == 0;
    refs_.push_back({o, sub, e->byte_length(), raw});
  };
  auto add_all = [&](uint16_t index, uint8_t from) {
    if (const coe::Object* o = od.find(index)) {
      for (const auto& e : o->entries()) {
        if (e.subindex >= from) add(index, e.subindex);
      }
    }
  };
  add(0x2000, 0x04);
  add(0x2000, 0x09);
  add(0x2000, 0x0B);
  for (const auto& r : config.rims) add(rim_info_index(r.number), 0x07);
  for (const auto& m : config.modules) {
    if (m.card->safe_state) {
      add_all(m.index(0x4000, static_cast<uint8_t>(*m.card->safe_state)), 1);
    }
    if (m.card->uart) add_all(m.index(0x5000, 5), 1);
  }
  for (uint16_t index : {0xF3A1, 0xF3A2, 0xF3A3, 0xF3A4, 0xF3A6, 0xF3A8}) add_all(index, 1);
  add_all(0xF030, 0);

  uLong crc = ::crc32(0L, Z_NULL, 0);
  for (const Ref& r : refs_) {
    const coe::Entry* e = r.object->entry(r.subindex);
    const uint8_t d[7] = {static_cast<uint8_t>(r.object->index()),
                          static_cast<uint8_t>(r.object->index() >> 8),
                          r.subindex,
                          static_cast<uint8_t>(e->data_type),
                          static_cast<uint8_t>(e->data_type >> 8),
                          static_cast<uint8_t>(e->bit_length),
                          static_cast<uint8_t>(e->bit_length >> 8)};
    crc = ::crc32(crc, d, sizeof d);
    payload_bytes_ += r.bytes;
  }
  fingerprint_ = static_cast<uint32_t>(crc);
}

std::vector<uint8_t> ParameterSet::capture() const {
  std::vector<uint8_t> out;
  out.reserve(payload_bytes_);
  for (const Ref& r : refs_) {
    if (r.raw) {
      const auto b = r.object->bytes(r.subindex);
      out.insert(out.end(), b.begin(), b.end());
    } else {
      uint8_t tmp[8];
      coe::put_le(tmp, 8, r.object->get_u(r.subindex));
      out.insert(out.end(), tmp, tmp + std::min<size_t>(r.bytes, 8));
      out.resize(out.size() + (r.bytes > 8 ? r.bytes - 8 : 0), 0);
    }
  }
  return out;
}

bool ParameterSet::apply(std::span<const uint8_t> payload) const {
  if (payload.size() != payload_bytes_) return false;
  size_t at = 0;
  for (const Ref& r : refs_) {
    if (r.raw) {
      auto b = r.object->bytes(r.subindex);
      std::copy_n(payload.begin() + static_cast<long>(at), b.size(), b.begin());
    } else {
      r.object->set_u(r.subindex, coe::get_le(payload.data() + at, std::min<size_t>(r.bytes, 8)));
    }
    at += r.bytes;
  }
  return true;
}

}  // namespace rackcat::mdp
