#include "coe/entry_check.hpp"

#include <algorithm>

#include "coe/bits.hpp"

namespace rackcat::coe {
namespace {

uint64_t read_bits(std::span<const uint8_t> image, size_t bit_offset, size_t bits) {
  uint8_t tmp[8] = {};
  bits = std::min<size_t>(bits, 64);
  if (bit_offset + bits > image.size() * 8) {
    return 0;
  }
  copy_bits(tmp, 0, image.data(), bit_offset, bits);
  return le::get(tmp, 8);
}

int64_t sign_extend(uint64_t raw, unsigned bits) {
  if (bits == 0 || bits >= 64) {
    return static_cast<int64_t>(raw);
  }
  const uint64_t sign = uint64_t{1} << (bits - 1);
  return static_cast<int64_t>((raw ^ sign) - sign);
}

bool entry_signed(const Entry& e) {
  return is_signed(e.type());
}

// Compares two values of `e`'s type: <0, 0, >0.
int compare(const Entry& e, uint64_t a, uint64_t b) {
  if (entry_signed(e)) {
    const int64_t x = sign_extend(a, e.bit_length), y = sign_extend(b, e.bit_length);
    return x < y ? -1 : (x > y ? 1 : 0);
  }
  return a < b ? -1 : (a > b ? 1 : 0);
}

}  // namespace

AbortCode check_read_access(uint16_t bits, EsmState state) {
  if (access::can_read(bits, state)) {
    return AbortCode::None;
  }
  return (bits & access::kReadAll) ? AbortCode::DeviceState : AbortCode::WriteOnly;
}

AbortCode check_write_access(uint16_t bits, EsmState state) {
  if (access::can_write(bits, state)) {
    return AbortCode::None;
  }
  return (bits & access::kWriteAll) ? AbortCode::DeviceState : AbortCode::ReadOnly;
}

bool is_integer_entry(const Entry& e) {
  if (is_enum_type(e.data_type)) {
    return true;
  }
  const DataType t = e.type();
  return fixed_bit_size(t).has_value() && !is_real(t);
}

int64_t effective_min(const Entry& e) {
  if (e.min) {
    return *e.min;
  }
  if (!entry_signed(e)) {
    return 0;
  }
  const unsigned bits = std::clamp<unsigned>(e.bit_length, 1, 64);
  return bits >= 64 ? INT64_MIN : -(int64_t{1} << (bits - 1));
}

int64_t effective_max(const Entry& e) {
  if (e.max) {
    return *e.max;
  }
  const unsigned bits = std::clamp<unsigned>(e.bit_length, 1, 64);
  if (entry_signed(e)) {
    return bits >= 64 ? INT64_MAX : (int64_t{1} << (bits - 1)) - 1;
  }
  return bits >= 64 ? static_cast<int64_t>(~uint64_t{0})
                    : static_cast<int64_t>((uint64_t{1} << bits) - 1);
}

AbortCode check_value(const ObjectDictionary& od, const Object& obj, const Entry& e,
                      std::span<const uint8_t> value, std::span<const uint8_t> image) {
  if (!is_integer_entry(e) || value.empty()) {
    return AbortCode::None;
  }
  const uint64_t raw = le::get(value.data(), std::min<size_t>(value.size(), 8));
  // A BOOLEAN/BITn value with bits beyond its width is not a value of the type.
  if (e.bit_length < 64 && e.bit_length % 8 != 0 && (raw >> e.bit_length) != 0) {
    return AbortCode::ValueRange;
  }
  // Subindex 0 of an ARRAY/RECORD counts entries: never more than exist.
  if (obj.code() != ObjectCode::Var && e.subindex == 0 && raw > obj.max_subindex()) {
    return AbortCode::ValueTooHigh;
  }
  if (is_enum_type(e.data_type)) {
    if (const EnumType* en = od.find_enum(e.data_type)) {
      const int64_t v = static_cast<int64_t>(raw);
      if (std::none_of(en->values.begin(), en->values.end(),
                       [&](const EnumValue& ev) { return ev.value == v; })) {
        return AbortCode::ValueRange;
      }
    }
  }
  if (entry_signed(e)) {
    const int64_t v = sign_extend(raw, e.bit_length);
    if (e.max && v > *e.max) {
      return AbortCode::ValueTooHigh;
    }
    if (e.min && v < *e.min) {
      return AbortCode::ValueTooLow;
    }
  } else {
    if (e.max && *e.max >= 0 && raw > static_cast<uint64_t>(*e.max)) {
      return AbortCode::ValueTooHigh;
    }
    if (e.max && *e.max < 0) {
      return AbortCode::ValueTooHigh;
    }
    if (e.min && *e.min > 0 && raw < static_cast<uint64_t>(*e.min)) {
      return AbortCode::ValueTooLow;
    }
  }
  // Paired limits: a maximum may not go below its minimum and vice versa.
  if (e.max_of) {
    if (const Entry* lo = obj.entry(e.max_of);
        lo && compare(e, raw, read_bits(image, lo->bit_offset, lo->bit_length)) < 0) {
      return AbortCode::MaxBelowMin;
    }
  }
  if (e.min_of) {
    if (const Entry* hi = obj.entry(e.min_of);
        hi && compare(e, raw, read_bits(image, hi->bit_offset, hi->bit_length)) > 0) {
      return AbortCode::MaxBelowMin;
    }
  }
  return AbortCode::None;
}

}  // namespace rackcat::coe
