// Small builders for the object tables of mdp/objects_*.cpp (internal to rackcat_mdp). They
// turn one line of the guide's Appendix A (subindex, name, type, access, default, PDO flag) into
// a coe::Entry, so the object files read like the guide's tables.
#pragma once

#include <cstdint>
#include <cstring>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "coe/access.hpp"
#include "coe/object_dictionary.hpp"
#include "coe/unit_code.hpp"

namespace rackcat::mdp::detail {

using coe::DataType;
using coe::Entry;
using coe::Object;
using coe::ObjectCode;

inline constexpr uint16_t kTx = coe::access::kTxPdoMappable;
inline constexpr uint16_t kRx = coe::access::kRxPdoMappable;

// The guide's access column ("ro", "rw", "ro,wr_preop", "ro, wr_op", "RO").
inline uint16_t acc(std::string_view guide) {
  const auto bits = coe::access::from_guide(guide);
  if (!bits) throw std::logic_error("bad guide access notation: " + std::string(guide));
  return *bits;
}

inline std::vector<uint8_t> le_bytes(uint64_t value, size_t n) {
  std::vector<uint8_t> out(n);
  for (size_t i = 0; i < n; ++i) out[i] = static_cast<uint8_t>(value >> (8 * i));
  return out;
}

// An integer/bit entry with a default value.
inline Entry num(uint8_t sub, std::string name, DataType type, uint16_t access, uint64_t def = 0) {
  const uint16_t bits = coe::fixed_bit_size(type).value_or(0);
  return coe::make_entry(sub, std::move(name), type, bits, access, le_bytes(def, (bits + 7) / 8));
}

// An integer entry limited to [lo, hi] (SDO writes outside answer 0x06090031/32).
inline Entry ranged(uint8_t sub, std::string name, DataType type, uint16_t access, uint64_t def,
                    int64_t lo, int64_t hi) {
  Entry e = num(sub, std::move(name), type, access, def);
  e.min = lo;
  e.max = hi;
  return e;
}

// An entry of a device enumeration type (0x0800..), `bits` wide.
inline Entry enum_entry(uint8_t sub, std::string name, uint16_t enum_index, uint16_t bits,
                        uint16_t access, uint64_t def) {
  return coe::make_entry(sub, std::move(name), static_cast<DataType>(enum_index), bits, access,
                         le_bytes(def, (bits + 7) / 8));
}

inline Entry real(uint8_t sub, std::string name, uint16_t access, float def = 0.0f) {
  Entry e = num(sub, std::move(name), DataType::Real32, access);
  uint32_t raw = 0;
  static_assert(sizeof raw == sizeof def);
  std::memcpy(&raw, &def, sizeof raw);
  e.default_value = le_bytes(raw, 4);
  return e;
}

// The entry with its ETG.1004 unit (coe/unit_code.hpp), for the ESI.
inline Entry with_unit(Entry e, uint32_t unit) {
  e.unit = unit;
  return e;
}

// VISIBLE_STRING(chars): fixed size on the wire, shorter text padded with NUL.
inline Entry str(uint8_t sub, std::string name, uint16_t chars, uint16_t access,
                 std::string_view def = {}) {
  std::vector<uint8_t> value(chars, 0);
  for (size_t i = 0; i < def.size() && i < chars; ++i) value[i] = static_cast<uint8_t>(def[i]);
  return coe::make_entry(sub, std::move(name), DataType::VisibleString,
                         static_cast<uint16_t>(chars * 8), access, std::move(value));
}

// OCTET_STRING(bytes): the guide's "ARRAY [0..n] OF BYTE" command entries and sample arrays.
inline Entry octets(uint8_t sub, std::string name, uint16_t bytes, uint16_t access,
                    std::span<const uint8_t> def = {}) {
  std::vector<uint8_t> value(bytes, 0);
  for (size_t i = 0; i < def.size() && i < bytes; ++i) value[i] = def[i];
  return coe::make_entry(sub, std::move(name), DataType::OctetString,
                         static_cast<uint16_t>(bytes * 8), access, std::move(value));
}

// A gap of `bits` bits (the guide's pad_3 / pad_15 / Pad_4 rows): takes its place in the
// layout, answers SDO access with "subindex does not exist".
inline Entry pad(uint8_t sub, uint16_t bits) {
  Entry e = coe::make_entry(sub, "Padding", DataType{}, bits, 0);
  e.padding = true;
  return e;
}

// Subindex 0 of an ARRAY/RECORD: the number of entries in use.
inline Entry sub0(uint8_t count, uint16_t access = coe::access::kRo) {
  return num(0, "Number of entries", DataType::Unsigned8, access, count);
}

inline Object var(uint16_t index, std::string name, Entry e) {
  Object o(index, ObjectCode::Var, std::move(name), e.data_type);
  e.subindex = 0;
  o.add(std::move(e));
  o.finalize();
  return o;
}

// The candidate bytes of `sub` in a write: the single-entry data itself, or its slice of the
// complete-access candidate image (subindex -1). Empty when the write does not touch `sub`.
inline std::span<const uint8_t> written_bytes(const Object& obj, uint8_t sub, int subindex,
                                              std::span<const uint8_t> data) {
  if (subindex == sub) return data;
  if (subindex != -1) return {};
  const Entry* e = obj.entry(sub);
  if (!e || e->bit_offset % 8 != 0) return {};
  const size_t first = e->bit_offset / 8;
  if (first + e->byte_length() > data.size()) return {};
  return data.subspan(first, e->byte_length());
}

// Text of a VISIBLE_STRING value: up to the first NUL.
inline std::string_view as_text(std::span<const uint8_t> bytes) {
  size_t n = 0;
  while (n < bytes.size() && bytes[n] != 0) ++n;
  return {reinterpret_cast<const char*>(bytes.data()), n};
}

}  // namespace rackcat::mdp::detail
