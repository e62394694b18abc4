// Complete access reads and writes of ARRAY and RECORD objects (ETG.1000.6 §5.6.2.1.4,
// §5.6.2.2.4).
#include "coe/complete_access.hpp"

#include <algorithm>
#include <array>
#include <cstring>

#include "coe/bits.hpp"
#include "coe/entry_check.hpp"
#include "coe/sdo_server.hpp"

namespace rackcat::coe {
namespace {

size_t entry_bits(const Object& obj, const Entry& e) {
  // Only the 8 value bits of subindex 0 are data; the following 8 are padding.
  return (obj.code() != ObjectCode::Var && e.subindex == 0) ? 8 : e.bit_length;
}

bool bits_equal(const uint8_t* a, const uint8_t* b, size_t bit_offset, size_t bits) {
  for (size_t i = bit_offset; i < bit_offset + bits; ++i) {
    if (((a[i / 8] ^ b[i / 8]) >> (i % 8)) & 1u) {
      return false;
    }
  }
  return true;
}

}  // namespace

uint8_t ca_last_subindex(const Object& obj) {
  return std::min(obj.sub0(), obj.max_subindex());
}

size_t ca_bytes(const Object& obj, uint8_t subindex, uint8_t last) {
  const size_t begin = ca_begin_bit(subindex);
  const size_t end = std::max(obj.ca_end_bit(last), begin);
  return (end - begin + 7) / 8;
}

void ca_extract(const Object& obj, uint8_t first, uint8_t last, uint8_t* out) {
  std::memset(out, 0, ca_bytes(obj, first, last));
  const size_t begin = ca_begin_bit(first);
  const uint8_t* image = obj.image().data();
  for (const Entry& e : obj.entries()) {
    if (e.subindex < first || e.padding) {
      continue;
    }
    if (e.subindex > last) {
      break;
    }
    copy_bits(out, e.bit_offset - begin, image, e.bit_offset, entry_bits(obj, e));
  }
}

AbortCode SdoServer::read_complete(Object& obj, uint8_t subindex, EsmState state, size_t& bytes) {
  if (obj.code() == ObjectCode::Var) {
    return AbortCode::CompleteAccessUnsupported;
  }
  if (subindex > 1) {
    return AbortCode::UnsupportedAccess;
  }
  if (obj.hooks().before_read) {
    obj.hooks().before_read(obj, -1);
  }
  const uint8_t last = ca_last_subindex(obj);
  for (const Entry& e : obj.entries()) {
    if (e.subindex < subindex || e.padding) {
      continue;
    }
    if (e.subindex > last) {
      break;
    }
    if (AbortCode rc = check_read_access(e.access, state); rc != AbortCode::None) {
      return rc;
    }
  }
  bytes = ca_bytes(obj, subindex, last);
  return AbortCode::None;
}

AbortCode SdoServer::write_complete(Object& obj, uint8_t subindex, std::span<const uint8_t> data,
                                    EsmState state) {
  if (obj.code() == ObjectCode::Var) {
    return AbortCode::CompleteAccessUnsupported;
  }
  if (subindex > 1) {
    return AbortCode::UnsupportedAccess;
  }
  const auto image = obj.image();
  // The candidate image lives on the stack, or for objects larger than that in a buffer
  // reserved at start-up (prepare()).
  if (image.size() > capacity_) {
    return AbortCode::OutOfMemory;
  }
  std::array<uint8_t, kStackScratch> local_cand;  // written before it is read
  std::array<uint8_t, kStackScratch> local_value;
  const uint8_t max_sub = obj.max_subindex();
  uint8_t last = ca_last_subindex(obj);
  if (subindex == 0) {
    if (data.empty()) {
      return AbortCode::LengthTooLow;
    }
    // The written subindex 0 says how many entries follow.
    if (data[0] > max_sub) {
      return AbortCode::ValueTooHigh;
    }
    last = data[0];
  }
  // Enough data for every entry in use, and no more than the whole object.
  if (data.size() < ca_bytes(obj, subindex, last)) {
    return AbortCode::LengthTooLow;
  }
  if (data.size() > ca_bytes(obj, subindex, max_sub)) {
    return AbortCode::LengthTooHigh;
  }

  const size_t begin = ca_begin_bit(subindex);
  uint8_t* cand = image.size() <= local_cand.size() ? local_cand.data() : scratch_.data();
  std::memcpy(cand, image.data(), image.size());
  for (const Entry& e : obj.entries()) {
    if (e.subindex < subindex || e.padding) {
      continue;
    }
    if (e.subindex > last) {
      break;
    }
    const size_t bits = entry_bits(obj, e);
    copy_bits(cand, e.bit_offset, data.data(), e.bit_offset - begin, bits);
    // An entry written with its current value passes even where it is read-only: masters
    // write back a whole record they read (e.g. 0x1C12 with its read-only subindex 0).
    if (bits_equal(cand, image.data(), e.bit_offset, bits)) {
      continue;
    }
    if (AbortCode rc = check_write_access(e.access, state); rc != AbortCode::None) {
      return rc;
    }
    uint8_t* value = e.byte_length() <= local_value.size() ? local_value.data() : value_.data();
    std::memset(value, 0, e.byte_length());
    copy_bits(value, 0, cand, e.bit_offset, bits);
    if (AbortCode rc = check_value(od_, obj, e, {value, e.byte_length()}, {cand, image.size()});
        rc != AbortCode::None) {
      return rc;
    }
  }
  if (obj.hooks().validate_write) {
    if (AbortCode rc = obj.hooks().validate_write(obj, -1, {cand, image.size()}, state);
        rc != AbortCode::None) {
      return rc;
    }
  }
  std::memcpy(image.data(), cand, image.size());
  if (obj.hooks().after_write) {
    obj.hooks().after_write(obj, -1);
  }
  return AbortCode::None;
}

}  // namespace rackcat::coe
