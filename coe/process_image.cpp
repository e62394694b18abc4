#include "coe/process_image.hpp"

#include <algorithm>
#include <cstring>

#include "base/short_copy.hpp"
#include "coe/bits.hpp"

namespace rackcat::coe {
namespace {

// A copy between the process data and an object image. Whole bytes of at most 8 (every
// mapped entry of a digital card, most records) go through base::copy_bytes's fixed-size
// moves instead of a libc call: the cyclic path does a few of these per slave and frame
// (issue 16). Everything else: copy_bits.
inline void copy_entry(uint8_t* dst, size_t dst_bit, const uint8_t* src, size_t src_bit,
                       size_t nbits) {
  if (((dst_bit | src_bit | nbits) % 8) == 0 && nbits != 0 && nbits <= 64) {
    base::copy_bytes(dst + dst_bit / 8, src + src_bit / 8, nbits / 8);
    return;
  }
  copy_bits(dst, dst_bit, src, src_bit, nbits);
}

// Zeroes the first n bytes (the input image before its copies), short ones without libc.
inline void zero_bytes(uint8_t* p, size_t n) {
  constexpr uint32_t kZero32 = 0;
  constexpr uint16_t kZero16 = 0;
  if (n > 8) {
    std::memset(p, 0, n);
  } else if (n >= 4) {
    std::memcpy(p, &kZero32, 4);
    std::memcpy(p + n - 4, &kZero32, 4);
  } else if (n >= 2) {
    std::memcpy(p, &kZero16, 2);
    std::memcpy(p + n - 2, &kZero16, 2);
  } else if (n == 1) {
    p[0] = 0;
  }
}

}  // namespace

AbortCode ProcessImage::compile_direction(PdoDirection dir, Direction& out) {
  const uint16_t assign_index = dir == PdoDirection::Rx ? kRxPdoAssign : kTxPdoAssign;
  const Object* assign = od_.find(assign_index);
  if (!assign) {
    return AbortCode::None;  // no assignment object: no process data this way
  }
  for (uint8_t i = 1; i <= assign->sub0() && i <= assign->max_subindex(); ++i) {
    const uint16_t mapping_index = static_cast<uint16_t>(assign->get_u(i));
    if (!is_mapping_index(mapping_index, dir)) {
      return AbortCode::ParameterIncompatible;
    }
    const Object* mapping = od_.find(mapping_index);
    if (!mapping) {
      return AbortCode::ObjectNotFound;
    }
    for (uint8_t j = 1; j <= mapping->sub0() && j <= mapping->max_subindex(); ++j) {
      const uint32_t value = static_cast<uint32_t>(mapping->get_u(j));
      const Entry* target = nullptr;
      if (AbortCode rc = check_mapping_entry(od_, value, dir, &target); rc != AbortCode::None) {
        return rc;
      }
      const MappingEntry m = MappingEntry::decode(value);
      if (target) {
        Object* obj = od_.find(m.index);
        uint8_t* image = obj->image().data();
        // Merge with the previous copy when both sides continue it (whole records mapped in
        // order become one memcpy).
        if (!out.copies.empty()) {
          Copy& prev = out.copies.back();
          if (prev.image == image && prev.image_bit + prev.bits == target->bit_offset &&
              prev.pd_bit + prev.bits == out.bits) {
            prev.bits += m.bits;
            out.bits += m.bits;
            continue;
          }
        }
        out.copies.push_back(
            Copy{image, target->bit_offset, static_cast<uint32_t>(out.bits), m.bits});
        const bool hooked = dir == PdoDirection::Rx ? static_cast<bool>(obj->hooks().after_write)
                                                    : static_cast<bool>(obj->hooks().before_read);
        if (hooked && std::find(out.hooked.begin(), out.hooked.end(), obj) == out.hooked.end()) {
          out.hooked.push_back(obj);
        }
      }
      out.bits += m.bits;
    }
  }
  return AbortCode::None;
}

AbortCode ProcessImage::compile(PdoDirection* failed) {
  Direction rx, tx;
  if (AbortCode rc = compile_direction(PdoDirection::Rx, rx); rc != AbortCode::None) {
    if (failed) {
      *failed = PdoDirection::Rx;
    }
    return rc;
  }
  if (AbortCode rc = compile_direction(PdoDirection::Tx, tx); rc != AbortCode::None) {
    if (failed) {
      *failed = PdoDirection::Tx;
    }
    return rc;
  }
  outputs_ = std::move(rx.copies);
  output_hooks_ = std::move(rx.hooked);
  output_bits_ = rx.bits;
  inputs_ = std::move(tx.copies);
  input_hooks_ = std::move(tx.hooked);
  input_bits_ = tx.bits;
  return AbortCode::None;
}

void ProcessImage::write_outputs(std::span<const uint8_t> sm2) {
  const size_t avail = sm2.size() * 8;
  for (const Copy& c : outputs_) {
    if (c.pd_bit + c.bits > avail) {
      break;  // copies are in process-data order
    }
    copy_entry(c.image, c.image_bit, sm2.data(), c.pd_bit, c.bits);
  }
  for (Object* obj : output_hooks_) {
    obj->hooks().after_write(*obj, ObjectHooks::kProcessData);
  }
}

void ProcessImage::read_inputs(std::span<uint8_t> sm3) {
  for (Object* obj : input_hooks_) {
    obj->hooks().before_read(*obj, ObjectHooks::kProcessData);
  }
  zero_bytes(sm3.data(), std::min(sm3.size(), input_bytes()));
  const size_t avail = sm3.size() * 8;
  for (const Copy& c : inputs_) {
    if (c.pd_bit + c.bits > avail) {
      break;
    }
    copy_entry(sm3.data(), c.pd_bit, c.image, c.image_bit, c.bits);
  }
}

bool ProcessImage::maps_input(const Object& o) const {
  const uint8_t* image = o.image().data();
  return std::any_of(inputs_.begin(), inputs_.end(),
                     [image](const Copy& c) { return c.image == image; });
}

}  // namespace rackcat::coe
