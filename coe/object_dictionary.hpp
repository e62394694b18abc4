// The object dictionary core (ETG.1000.6 §5.6.7). Objects are VAR, ARRAY or RECORD; every
// object keeps its value in one byte image laid out exactly as a complete access transfers it
// (ETG.1000.6 §5.6.2.1.4): entries at their bit offsets, subindex 0 of an ARRAY/RECORD in the
// first 16 bits (8 bits value + 8 bits padding). Reads and writes of single entries and of the
// whole object therefore share one representation and one code path.
//
// The dictionary knows nothing of ESC registers or mailboxes; the SDO server (sdo_server.hpp)
// is its only wire-facing client. Build it once at start-up; the request path then allocates
// nothing.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "coe/abort_code.hpp"
#include "coe/access.hpp"
#include "coe/data_type.hpp"

namespace rackcat::coe {

// ETG.1000.6 §5.6.3.5.2 object codes.
enum class ObjectCode : uint8_t { Var = 7, Array = 8, Record = 9 };

// One value of a device enumeration (ETG.2000 EnumInfo): 0x0800 DT0800EN04 etc.
struct EnumValue {
  int64_t value;
  std::string name;
};
struct EnumType {
  uint16_t index;      // 0x0800..
  std::string name;    // "DT0800EN04"
  uint16_t bit_size;   // 8 or 16 ...
  std::vector<EnumValue> values;
};

struct Entry {
  uint8_t subindex = 0;
  std::string name;
  uint16_t data_type = 0;   // a DataType value or an enum type index (0x0800+)
  uint16_t bit_length = 0;  // bits on the wire (strings: 8 * bytes)
  uint16_t bit_offset = 0;  // position inside the object's image
  uint16_t access = 0;      // access:: bits (ObjectAccess word, incl. PDO mappable flags)
  std::vector<uint8_t> default_value;  // little-endian bytes, (bit_length+7)/8 long, or empty
  std::optional<int64_t> min;          // integer range check on write (nullopt = type range)
  std::optional<int64_t> max;
  bool padding = false;  // a gap entry: counted in the layout, never addressed by SDO
  std::string unit;      // optional, for descriptions

  DataType type() const { return static_cast<DataType>(data_type); }
  uint16_t byte_length() const { return static_cast<uint16_t>((bit_length + 7) / 8); }
};

class Object;

// Live values and command objects. All hooks are optional; a hook runs on the request path and
// must not allocate.
struct ObjectHooks {
  // Refresh the image before `subindex` (or, for complete access, all entries: subindex -1)
  // is read.
  std::function<void(Object&, int subindex)> before_read;
  // Validate a write before it is committed: `data` is the new bytes for `subindex` (or the
  // whole image from subindex 0/1 for complete access, subindex -1). Return AbortCode::None to
  // accept. The state is the ESM state the write arrives in.
  std::function<AbortCode(const Object&, int subindex, std::span<const uint8_t> data,
                          EsmState state)>
      validate_write;
  // Runs after the bytes have been committed to the image.
  std::function<void(Object&, int subindex)> after_write;
};

class Object {
 public:
  Object(uint16_t index, ObjectCode code, std::string name, uint16_t data_type = 0);

  uint16_t index() const { return index_; }
  ObjectCode code() const { return code_; }
  const std::string& name() const { return name_; }
  // VAR: the value's type; ARRAY: the element type; RECORD: the record's type index (may be 0).
  uint16_t data_type() const { return data_type_; }

  // Add entries in subindex order. For ARRAY/RECORD add subindex 0 first (UNSIGNED8, 8 bits);
  // the builder places it in 16 bits as complete access requires. Bit offsets are assigned
  // automatically when `entry.bit_offset` is 0 and it is not the first entry; entries of 8
  // bits or more start on a byte boundary unless `packed` (PDO-style BITn packing).
  Entry& add(Entry entry);
  // Call once after the last add(): sizes the image and loads defaults.
  void finalize();

  const std::vector<Entry>& entries() const { return entries_; }
  const Entry* entry(uint8_t subindex) const;
  // Highest subindex defined (ETG.1000.6 "MaxSubindex" of SDO information).
  uint8_t max_subindex() const;
  // For ARRAY/RECORD: the current value of subindex 0 (number of entries in use).
  uint8_t sub0() const;

  // The value image, complete-access layout.
  std::span<uint8_t> image() { return image_; }
  std::span<const uint8_t> image() const { return image_; }
  size_t bit_size() const { return image_.size() * 8; }

  // Typed helpers for device code (little-endian, by subindex).
  std::span<uint8_t> bytes(uint8_t subindex);
  std::span<const uint8_t> bytes(uint8_t subindex) const;
  uint64_t get_u(uint8_t subindex) const;
  int64_t get_i(uint8_t subindex) const;
  void set_u(uint8_t subindex, uint64_t value);
  void set_string(uint8_t subindex, std::string_view text);
  std::string get_string(uint8_t subindex) const;
  // Reset every entry to its default.
  void load_defaults();

  ObjectHooks hooks;

 private:
  uint16_t index_;
  ObjectCode code_;
  std::string name_;
  uint16_t data_type_;
  std::vector<Entry> entries_;
  std::vector<uint8_t> image_;
};

class ObjectDictionary {
 public:
  // Adds an object (call Object::finalize() first or let add() do it). Replaces nothing:
  // adding an index twice throws std::logic_error (a programming error at start-up).
  Object& add(Object object);
  void add_enum(EnumType type);

  Object* find(uint16_t index);
  const Object* find(uint16_t index) const;

  // Objects in index order (for SDO Information lists, the `od` command and the ESI).
  template <class F>
  void for_each(F&& f) const {
    for (const auto& [index, obj] : objects_) f(obj);
  }
  template <class F>
  void for_each(F&& f) {
    for (auto& [index, obj] : objects_) f(obj);
  }
  size_t size() const { return objects_.size(); }
  const std::map<uint16_t, EnumType>& enums() const { return enums_; }

 private:
  std::map<uint16_t, Object> objects_;
  std::map<uint16_t, EnumType> enums_;
};

}  // namespace rackcat::coe
