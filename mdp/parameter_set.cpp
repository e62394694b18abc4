#include "mdp/parameter_set.hpp"

#include <zlib.h>

#include <fmt/format.h>

#include <algorithm>

#include "coe/bits.hpp"
#include "coe/entry_check.hpp"
#include "mdp/substitute_values.hpp"

namespace rackcat::mdp {

ParameterSet::ParameterSet(coe::ObjectDictionary& od, const RackConfig& config) : od_(&od) {
  auto add = [&](uint16_t index, uint8_t sub) {
    coe::Object* o = od.find(index);
    const coe::Entry* e = o ? o->entry(sub) : nullptr;
    if (!e || e->padding) return;
    const bool raw = e->bit_offset % 8 == 0 && e->bit_length % 8 == 0;
    push({o, sub, e->byte_length(), raw});
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
    // Substitute values (mdp/substitute_values.hpp); the status 0x4nnC is live, not stored.
    for (uint8_t nibble :
         {substitute::kOutputReaction, substitute::kInputReaction, substitute::kInputValue}) {
      add_all(m.index(0x4000, nibble), 1);
    }
    // Encoder settings and the preset's offset (encoder guide 3.11.7: stored non-volatile).
    if (m.card->encoder()) {
      add_all(m.index(0x8000, 0), 1);
      add(m.index(0x8000, 1), 0x01);
    }
  }
  for (uint16_t index : {0xF3A1, 0xF3A2, 0xF3A3, 0xF3A4, 0xF3A6, 0xF3A8}) add_all(index, 1);
  add_all(0xF030, 0);
  runs_.shrink_to_fit();

  uLong crc = ::crc32(0L, Z_NULL, 0);
  for_each_ref([&](const Ref& r) {
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
  });
  fingerprint_ = static_cast<uint32_t>(crc);
}

void ParameterSet::push(const Ref& ref) {
  ++count_;
  if (!runs_.empty()) {
    Run& last = runs_.back();
    if (last.object == ref.object && last.bytes == ref.bytes && last.raw == ref.raw &&
        last.last + 1 == ref.subindex) {
      last.last = ref.subindex;
      return;
    }
  }
  runs_.push_back({ref.object, ref.subindex, ref.subindex, ref.bytes, ref.raw});
}

std::vector<uint8_t> ParameterSet::capture() const {
  std::vector<uint8_t> out;
  out.reserve(payload_bytes_);
  for_each_ref([&](const Ref& r) {
    if (r.raw) {
      const auto b = r.object->bytes(r.subindex);
      out.insert(out.end(), b.begin(), b.end());
    } else {
      uint8_t tmp[8];
      le::put(tmp, 8, r.object->get_u(r.subindex));
      out.insert(out.end(), tmp, tmp + std::min<size_t>(r.bytes, 8));
      out.resize(out.size() + (r.bytes > 8 ? r.bytes - 8 : 0), 0);
    }
  });
  return out;
}

bool ParameterSet::apply(std::span<const uint8_t> payload) const {
  if (payload.size() != payload_bytes_) return false;
  size_t at = 0;
  for_each_ref([&](const Ref& r) {
    if (r.raw) {
      auto b = r.object->bytes(r.subindex);
      std::copy_n(payload.begin() + static_cast<long>(at), b.size(), b.begin());
    } else {
      r.object->set_u(r.subindex, le::get(payload.data() + at, std::min<size_t>(r.bytes, 8)));
    }
    at += r.bytes;
  });
  return true;
}

std::string ParameterSet::check(std::span<const uint8_t> payload) const {
  if (payload.size() != payload_bytes_) {
    return fmt::format("{} bytes of parameters where this rack has {}", payload.size(),
                       payload_bytes_);
  }
  // Object by object: the candidate image with every stored entry of the object in place, each
  // entry checked against it (paired limits see their partner's new value), then the object's
  // hook as for a complete access writing the whole candidate (ETG.1000.6 §5.6.2.1).
  size_t at = 0;
  size_t i = 0;
  std::vector<uint8_t> candidate;
  std::vector<uint8_t> value;
  while (i < runs_.size()) {
    const coe::Object& obj = *runs_[i].object;
    const auto image = obj.image();
    candidate.assign(image.begin(), image.end());
    size_t end = i;
    for (; end < runs_.size() && runs_[end].object == &obj; ++end) {
    }
    // The object's parameters, in payload order.
    auto for_each_of_object = [&](auto&& f) {
      for (size_t k = i; k < end; ++k) {
        const Run& run = runs_[k];
        for (unsigned sub = run.first; sub <= run.last; ++sub) {
          f(Ref{run.object, static_cast<uint8_t>(sub), run.bytes, run.raw});
        }
      }
    };
    size_t end_at = at;
    for_each_of_object([&](const Ref& r) {
      const coe::Entry& e = *obj.entry(r.subindex);
      value.assign(e.byte_length(), 0);
      if (r.raw) {
        std::copy_n(payload.begin() + static_cast<long>(end_at), value.size(), value.begin());
      } else {
        le::put(value.data(), std::min<size_t>(value.size(), 8),
                le::get(payload.data() + end_at, std::min<size_t>(r.bytes, 8)));
      }
      coe::copy_bits(candidate.data(), e.bit_offset, value.data(), 0, e.bit_length);
      end_at += r.bytes;
    });
    std::string refused;
    for_each_of_object([&](const Ref& r) {
      if (!refused.empty()) return;
      const coe::Entry& e = *obj.entry(r.subindex);
      value.assign(e.byte_length(), 0);
      coe::copy_bits(value.data(), 0, candidate.data(), e.bit_offset, e.bit_length);
      if (const auto rc = coe::check_value(*od_, obj, e, value, candidate);
          rc != coe::AbortCode::None) {
        refused = fmt::format("0x{:04X}:{:02X} refused as an SDO write would be (abort 0x{:08X})",
                              obj.index(), r.subindex, static_cast<uint32_t>(rc));
      }
    });
    if (!refused.empty()) return refused;
    if (obj.hooks().validate_write) {
      if (const auto rc = obj.hooks().validate_write(obj, -1, candidate, EsmState::PreOp);
          rc != coe::AbortCode::None) {
        return fmt::format("0x{:04X} refused as an SDO write would be (abort 0x{:08X})",
                           obj.index(), static_cast<uint32_t>(rc));
      }
    }
    i = end;
    at = end_at;
  }
  return {};
}

}  // namespace rackcat::mdp
