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
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "coe/abort_code.hpp"
#include "coe/access.hpp"
#include "coe/data_type.hpp"
#include "coe/object_image.hpp"

namespace rackcat::coe {

// ETG.1000.6 §5.6.3.5.2 object codes.
enum class ObjectCode : uint8_t { Var = 7, Array = 8, Record = 9 };

// One value of a device enumeration (ETG.2000 EnumInfo): 0x0800 DT0800EN04 etc.
struct EnumValue {
  int64_t value;
  std::string name;
};
struct EnumType {
  uint16_t index;     // 0x0800..
  std::string name;   // "DT0800EN04"
  uint16_t bit_size;  // 8 or 16 ...
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
  // ETG.1004 unit code (coe/unit_code.hpp) the ESI gives the entry, 0 = none.
  uint32_t unit = 0;
  // Paired limits (abort 0x06090036 "maximum value is less than minimum value"): when
  // non-zero, this entry is the maximum of the pair and subindex `max_of` holds the minimum
  // (a write below it aborts), or this entry is the minimum and `min_of` names the maximum.
  uint8_t max_of = 0;
  uint8_t min_of = 0;
  // The UNSIGNED16 unit type of SDO Information entry descriptions (ETG.1000.6 §5.6.3.6.2),
  // 0 = none. How it relates to the 32-bit `unit` is not in our references (docs/MDP.md Units).
  uint16_t unit_type = 0;

  DataType type() const { return static_cast<DataType>(data_type); }
  bool operator==(const Entry&) const = default;
  uint16_t byte_length() const { return static_cast<uint16_t>((bit_length + 7) / 8); }
};

// An entry with the fields every dictionary sets (the optional ones stay at their defaults).
inline Entry make_entry(uint8_t subindex, std::string name, DataType type, uint16_t bits,
                        uint16_t access, std::vector<uint8_t> default_value = {}) {
  Entry e;
  e.subindex = subindex;
  e.name = std::move(name);
  e.data_type = static_cast<uint16_t>(type);
  e.bit_length = bits;
  e.access = access;
  e.default_value = std::move(default_value);
  return e;
}

class Object;

// What an object is, apart from its index and its values: name, object code, type, entry
// descriptions and layout (ETG.1000.6 §5.6.3.5, §5.6.3.6). Identical devices describe their
// objects identically, so a description is shared by every object that has it (interned when
// the object enters a dictionary, coe/shared_entries.hpp); only the index, the value image and
// the hooks are per object.
struct ObjectDescription {
  std::string name;
  // The entry descriptions, themselves shared between objects listing identical entries.
  std::shared_ptr<const std::vector<Entry>> entries;
  uint16_t data_type = 0;
  uint16_t combined_access = 0;
  uint16_t next_bit = 0;
  ObjectCode code = ObjectCode::Var;
  bool packed = false;
};

// Live values and command objects. All hooks are optional; a hook runs on the request path and
// must not allocate. Most objects of a device have none, so an object holds its hooks out of
// line, allocated when the first one is set (Object::edit_hooks).
struct ObjectHooks {
  // The subindex the process image passes to before_read/after_write of a mapped object on the
  // cyclic path (every cycle, all mapped entries at once): refresh or consume only what can be
  // mapped, without allocating or formatting.
  static constexpr int kProcessData = -2;
  // Refresh the image before `subindex` (or, for complete access, all entries: subindex -1;
  // for the process data, kProcessData) is read.
  std::function<void(Object&, int subindex)> before_read;
  // Validate a write before it is committed: `data` is the new bytes for `subindex`
  // (byte_length() bytes, a bit entry right-aligned in one byte), or for complete access
  // (subindex -1) the whole candidate image, laid out exactly like image() from subindex 0,
  // whether the master wrote from subindex 0 or 1. Return AbortCode::None to accept. The state
  // is the ESM state the write arrives in.
  std::function<AbortCode(const Object&, int subindex, std::span<const uint8_t> data,
                          EsmState state)>
      validate_write;
  // Runs after the bytes have been committed to the image.
  std::function<void(Object&, int subindex)> after_write;
};

class Object {
 public:
  Object(uint16_t index, ObjectCode code, std::string name, uint16_t data_type = 0);
  Object(const Object& other);
  Object& operator=(const Object& other);
  Object(Object&&) noexcept = default;
  Object& operator=(Object&&) noexcept = default;
  ~Object() = default;

  uint16_t index() const { return index_; }
  ObjectCode code() const { return desc_->code; }
  const std::string& name() const { return desc_->name; }
  // VAR: the value's type; ARRAY: the element type; RECORD: the record's type index (may be 0).
  uint16_t data_type() const { return desc_->data_type; }

  // Add entries in subindex order. For ARRAY/RECORD add subindex 0 first (UNSIGNED8, 8 bits);
  // the builder places it in 16 bits as complete access requires. Bit offsets are assigned
  // automatically when `entry.bit_offset` is 0 and it is not the first entry; entries of 8
  // bits or more start on a byte boundary unless set_packed(true) (PDO-style BITn packing,
  // as ETG.2000 BitOffs of a packed record). An explicit bit_offset leaves a gap: gap bits
  // read as 0 in a complete access and are ignored on write. Entries marked `padding` take
  // their place in the layout but answer SDO access with "subindex does not exist".
  // Throws std::logic_error on a subindex out of order or an overlapping explicit offset.
  Entry& add(Entry entry);
  // Call once after the last add(): sizes the image and loads defaults. add() after
  // finalize() is allowed (finalize again).
  void finalize();
  void set_packed(bool packed);
  bool packed() const { return desc_->packed; }

  const std::vector<Entry>& entries() const { return *desc_->entries; }
  // Shares the description with every other object described identically (see
  // coe/shared_entries.hpp; ObjectDictionary::add calls it). add() afterwards copies it first.
  void share_entries();
  const Entry* entry(uint8_t subindex) const;
  // Highest subindex defined (ETG.1000.6 "MaxSubindex" of SDO information).
  uint8_t max_subindex() const;
  // For ARRAY/RECORD: the current value of subindex 0 (number of entries in use).
  uint8_t sub0() const;
  // OR of all entries' access words (for SDO Information list types 2..5).
  uint16_t combined_access() const { return desc_->combined_access; }
  // Bits of the complete-access image covering subindex 0 (or 1) up to subindex `last`
  // (inclusive; entries above `last` excluded). Used for complete access lengths.
  size_t ca_end_bit(uint8_t last) const;

  // The value image, complete-access layout.
  std::span<uint8_t> image() { return image_.span(); }
  std::span<const uint8_t> image() const { return image_.span(); }
  size_t bit_size() const { return image_.size() * 8; }

  // Typed helpers for device code (little-endian, by subindex). bytes() is the entry's byte
  // range inside the image: exact for byte-aligned entries; for a bit entry (BOOL/BITn) it is
  // the byte holding it, so use get_u/set_u for those. Unknown subindex: empty span.
  std::span<uint8_t> bytes(uint8_t subindex);
  std::span<const uint8_t> bytes(uint8_t subindex) const;
  uint64_t get_u(uint8_t subindex) const;
  int64_t get_i(uint8_t subindex) const;
  void set_u(uint8_t subindex, uint64_t value);
  void set_string(uint8_t subindex, std::string_view text);
  std::string get_string(uint8_t subindex) const;
  // Reset every entry to its default.
  void load_defaults();
  // Replaces the default of `subindex` (byte_length() bytes LE, shorter zero-filled, longer cut);
  // the image changes at the next load_defaults(). False for an unknown subindex. For power-on
  // values a device reset may change (a new firmware's version, the enumerated modules).
  bool set_default(uint8_t subindex, std::span<const uint8_t> value);

  // The hooks the request and cyclic paths call (all empty when none was set).
  const ObjectHooks& hooks() const { return hooks_ ? *hooks_ : kNoHooks; }
  // The hooks to set or replace, at start-up: allocates them on the first call.
  ObjectHooks& edit_hooks();

 private:
  static const ObjectHooks kNoHooks;

  // The description, copied first when it is shared (copy-on-write).
  ObjectDescription& writable_description();
  std::vector<Entry>& writable_entries();

  uint16_t index_;
  bool shared_ = false;          // desc_ is interned: never changed in place
  bool entries_shared_ = false;  // desc_->entries is interned: never changed in place
  ObjectImage image_;
  std::shared_ptr<const ObjectDescription> desc_;
  std::unique_ptr<ObjectHooks> hooks_;  // null: no hooks (most objects)
};

class ObjectDictionary {
 public:
  ObjectDictionary() = default;
  ObjectDictionary(const ObjectDictionary& other);
  ObjectDictionary& operator=(const ObjectDictionary& other);
  ObjectDictionary(ObjectDictionary&&) = default;  // the objects stay where they are
  ObjectDictionary& operator=(ObjectDictionary&&) = default;

  // Adds an object (call Object::finalize() first or let add() do it). Replaces nothing:
  // adding an index twice throws std::logic_error (a programming error at start-up).
  // References returned stay valid for the dictionary's lifetime.
  Object& add(Object object);
  void add_enum(EnumType type);
  // Removes an object (e.g. a module unplugged at start-up); false if absent.
  bool remove(uint16_t index);

  // O(log n) over the sorted flat index: the SDO request path's lookup.
  Object* find(uint16_t index);
  const Object* find(uint16_t index) const;
  const EnumType* find_enum(uint16_t index) const;

  // Position-based access in index order (0 .. size()-1), for resumable SDO Information
  // lists; lower_bound gives the position of the first object with index >= `index`.
  const Object& at(size_t position) const { return *objects_[position]; }
  Object& at(size_t position) { return *objects_[position]; }
  size_t lower_bound(uint16_t index) const;
  // Largest object image in bytes (sizes the SDO server's transfer buffer).
  size_t max_image_bytes() const;

  // Objects in index order (for SDO Information lists, the `od` command and the ESI).
  template <class F>
  void for_each(F&& f) const {
    for (const auto& obj : objects_) {
      f(static_cast<const Object&>(*obj));
    }
  }
  template <class F>
  void for_each(F&& f) {
    for (auto& obj : objects_) {
      f(*obj);
    }
  }
  size_t size() const { return objects_.size(); }
  const std::map<uint16_t, EnumType>& enums() const { return enums_; }

 private:
  // Objects in index order, each in its own block: Object& stays valid across add() and
  // remove() of other objects. keys_ is the parallel index list the lookup searches.
  std::vector<std::unique_ptr<Object>> objects_;
  std::vector<uint16_t> keys_;
  std::map<uint16_t, EnumType> enums_;
};

}  // namespace rackcat::coe
