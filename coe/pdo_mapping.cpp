#include "coe/pdo_mapping.hpp"

#include "coe/bits.hpp"

namespace rackcat::coe {
namespace {

// Value of entry `sub` read from `image` (the object's current or candidate image).
uint64_t entry_value(const Object& obj, uint8_t sub, std::span<const uint8_t> image) {
  const Entry* e = obj.entry(sub);
  if (!e || e->bit_offset + e->bit_length > image.size() * 8) {
    return 0;
  }
  uint8_t tmp[8] = {};
  copy_bits(tmp, 0, image.data(), e->bit_offset, std::min<size_t>(e->bit_length, 64));
  return le::get(tmp, 8);
}

// The candidate image of `obj` after writing `data` to subindex `sub` (-1: data is the whole
// candidate image). Uses `buf` as storage; returns the candidate.
std::span<const uint8_t> candidate(const Object& obj, int sub, std::span<const uint8_t> data,
                                   std::span<uint8_t> buf) {
  if (sub < 0) {
    return data;
  }
  const auto img = obj.image();
  std::copy(img.begin(), img.end(), buf.begin());
  if (const Entry* e = obj.entry(static_cast<uint8_t>(sub))) {
    copy_bits(buf.data(), e->bit_offset, data.data(), 0,
              std::min<size_t>(e->bit_length, data.size() * 8));
  }
  return buf.first(img.size());
}

PdoDirection direction_of(uint16_t assign) {
  return assign == kRxPdoAssign ? PdoDirection::Rx : PdoDirection::Tx;
}

}  // namespace

bool is_mapping_index(uint16_t index, PdoDirection dir) {
  return dir == PdoDirection::Rx ? (index >= 0x1600 && index <= 0x17FF)
                                 : (index >= 0x1A00 && index <= 0x1BFF);
}

AbortCode check_mapping_entry(const ObjectDictionary& od, uint32_t value, PdoDirection dir,
                              const Entry** target) {
  const MappingEntry m = MappingEntry::decode(value);
  if (target) {
    *target = nullptr;
  }
  if (m.is_padding()) {
    return m.bits ? AbortCode::None : AbortCode::ParameterIncompatible;
  }
  const Object* obj = od.find(m.index);
  if (!obj) {
    return AbortCode::ObjectNotFound;
  }
  const Entry* e = obj->entry(m.subindex);
  if (!e || e->padding) {
    return AbortCode::SubindexNotFound;
  }
  const uint16_t flag = dir == PdoDirection::Rx ? access::kRxPdoMappable : access::kTxPdoMappable;
  if (!(e->access & flag)) {
    return AbortCode::NotMappable;
  }
  if (e->bit_length != m.bits) {
    return AbortCode::ParameterIncompatible;
  }
  if (target) {
    *target = e;
  }
  return AbortCode::None;
}

size_t mapping_bits(const ObjectDictionary& od, const Object& mapping, PdoDirection dir,
                    AbortCode& rc) {
  size_t bits = 0;
  rc = AbortCode::None;
  for (uint8_t i = 1; i <= mapping.sub0() && i <= mapping.max_subindex(); ++i) {
    const uint32_t v = static_cast<uint32_t>(mapping.get_u(i));
    if ((rc = check_mapping_entry(od, v, dir)) != AbortCode::None) {
      return 0;
    }
    bits += v & 0xFF;
  }
  return bits;
}

WriteValidator pdo_mapping_validator(const ObjectDictionary& od, PdoDirection dir,
                                     size_t max_bytes) {
  return
      [&od, dir, max_bytes](const Object& obj, int sub, std::span<const uint8_t> data, EsmState) {
        // CiA 301 / ETG.1000.6: entries change only while subindex 0 is 0.
        if (sub >= 1 && obj.sub0() != 0) {
          return AbortCode::SubindexZeroNotZero;
        }
        if (sub >= 1) {
          return check_mapping_entry(od, static_cast<uint32_t>(le::get(data.data(), 4)), dir);
        }
        uint8_t buf[2 + 255 * 4];
        const auto img = candidate(obj, sub, data, {buf, sizeof buf});
        const uint8_t n = img.empty() ? 0 : img[0];
        size_t bits = 0;
        for (uint8_t i = 1; i <= n; ++i) {
          const uint32_t v = static_cast<uint32_t>(entry_value(obj, i, img));
          if (AbortCode rc = check_mapping_entry(od, v, dir); rc != AbortCode::None) {
            return rc;
          }
          bits += v & 0xFF;
        }
        return bits > max_bytes * 8 ? AbortCode::PdoLengthExceeded : AbortCode::None;
      };
}

WriteValidator pdo_assign_validator(const ObjectDictionary& od, PdoDirection dir,
                                    size_t max_bytes) {
  return
      [&od, dir, max_bytes](const Object& obj, int sub, std::span<const uint8_t> data, EsmState) {
        if (sub >= 1 && obj.sub0() != 0) {
          return AbortCode::SubindexZeroNotZero;
        }
        uint8_t buf[2 + 255 * 2];
        const auto img = candidate(obj, sub, data, {buf, sizeof buf});
        const uint8_t first = sub >= 1 ? static_cast<uint8_t>(sub) : 1;
        const uint8_t last = sub >= 1 ? static_cast<uint8_t>(sub) : (img.empty() ? 0 : img[0]);
        size_t bits = 0;
        for (uint8_t i = first; i <= last && i >= first; ++i) {
          const uint16_t index = static_cast<uint16_t>(entry_value(obj, i, img));
          if (!is_mapping_index(index, dir)) {
            return AbortCode::ParameterIncompatible;
          }
          const Object* mapping = od.find(index);
          if (!mapping) {
            return AbortCode::ObjectNotFound;
          }
          AbortCode rc;
          bits += mapping_bits(od, *mapping, dir, rc);
          if (rc != AbortCode::None) {
            return rc;
          }
        }
        return bits > max_bytes * 8 ? AbortCode::PdoLengthExceeded : AbortCode::None;
      };
}

void install_pdo_validators(ObjectDictionary& od, size_t max_output_bytes, size_t max_input_bytes) {
  od.for_each([&](Object& obj) {
    const uint16_t i = obj.index();
    if (i == kRxPdoAssign || i == kTxPdoAssign) {
      const PdoDirection dir = direction_of(i);
      obj.edit_hooks().validate_write = pdo_assign_validator(
          od, dir, dir == PdoDirection::Rx ? max_output_bytes : max_input_bytes);
    } else if (is_mapping_index(i, PdoDirection::Rx)) {
      obj.edit_hooks().validate_write =
          pdo_mapping_validator(od, PdoDirection::Rx, max_output_bytes);
    } else if (is_mapping_index(i, PdoDirection::Tx)) {
      obj.edit_hooks().validate_write =
          pdo_mapping_validator(od, PdoDirection::Tx, max_input_bytes);
    }
  });
}

}  // namespace rackcat::coe
