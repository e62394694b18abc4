// Object images and the dictionary's sorted index (ETG.1000.6 §5.6.7, §5.6.2.1.4 for the
// complete-access layout the image follows).
#include "coe/object_dictionary.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>

#include "coe/bits.hpp"
#include "coe/shared_entries.hpp"

namespace rackcat::coe {

Object::Object(uint16_t index, ObjectCode code, std::string name, uint16_t data_type)
    : index_(index) {
  auto desc = std::make_shared<ObjectDescription>();
  desc->name = std::move(name);
  desc->entries = std::make_shared<std::vector<Entry>>();
  desc->data_type = data_type;
  desc->code = code;
  desc_ = std::move(desc);
}

const ObjectHooks Object::kNoHooks{};

Object::Object(const Object& other)
    : index_(other.index_),
      shared_(other.shared_),
      entries_shared_(other.entries_shared_),
      image_(other.image_),
      desc_(other.desc_),
      hooks_(other.hooks_ ? std::make_unique<ObjectHooks>(*other.hooks_) : nullptr) {}

Object& Object::operator=(const Object& other) {
  if (this != &other) {
    Object copy(other);
    *this = std::move(copy);
  }
  return *this;
}

ObjectHooks& Object::edit_hooks() {
  if (!hooks_) hooks_ = std::make_unique<ObjectHooks>();
  return *hooks_;
}

ObjectDescription& Object::writable_description() {
  if (shared_ || desc_.use_count() > 1) {
    desc_ = std::make_shared<ObjectDescription>(*desc_);
    shared_ = false;
  }
  // A description this object owns alone was created by make_shared of a non-const one (in
  // the constructor or above).
  return const_cast<ObjectDescription&>(*desc_);  // NOLINT(cppcoreguidelines-pro-type-const-cast)
}

std::vector<Entry>& Object::writable_entries() {
  ObjectDescription& desc = writable_description();
  // The entry list may be shared with objects of other descriptions: copy it first.
  if (entries_shared_ || desc.entries.use_count() > 1) {
    desc.entries = std::make_shared<std::vector<Entry>>(*desc.entries);
    entries_shared_ = false;
  }
  return const_cast<std::vector<Entry>&>(
      *desc.entries);  // NOLINT(cppcoreguidelines-pro-type-const-cast)
}

void Object::share_entries() {
  desc_ = intern_description(std::move(desc_));
  shared_ = true;
  entries_shared_ = true;
}

void Object::set_packed(bool packed) {
  if (desc_->packed != packed) writable_description().packed = packed;
}

Entry& Object::add(Entry e) {
  std::vector<Entry>& list = writable_entries();
  ObjectDescription& desc = const_cast<ObjectDescription&>(
      *desc_);  // NOLINT(cppcoreguidelines-pro-type-const-cast): writable since the line above
  const ObjectCode code = desc.code;
  uint16_t& next_bit = desc.next_bit;
  if (!list.empty() && e.subindex <= list.back().subindex) {
    throw std::logic_error("object " + std::to_string(index_) + ": subindex out of order");
  }
  if (e.bit_length == 0) {
    if (auto bits = fixed_bit_size(e.type())) {
      e.bit_length = *bits;
    } else if (!e.default_value.empty()) {
      e.bit_length = static_cast<uint16_t>(e.default_value.size() * 8);
    } else {
      throw std::logic_error("object " + std::to_string(index_) + ": entry without bit length");
    }
  }
  // Subindex 0 of an ARRAY/RECORD takes 16 bits in complete access (ETG.1000.6 §5.6.2.1.4).
  const bool sub0_slot = code != ObjectCode::Var && e.subindex == 0;
  if (list.empty() || e.bit_offset == 0) {
    uint16_t pos = list.empty() ? e.bit_offset : next_bit;
    // A padding entry fills the bits up to the next entry exactly (the guide's BIT1 + pad_15
    // of 0x2000:0B/0C are 16 bits together): it is never moved to a byte boundary.
    if (!desc.packed && !e.padding && e.bit_length >= 8 && (pos % 8) != 0) {
      pos = static_cast<uint16_t>(pos + 8 - pos % 8);
    }
    e.bit_offset = pos;
  } else if (e.bit_offset < next_bit) {
    throw std::logic_error("object " + std::to_string(index_) + ": overlapping bit offset");
  }
  next_bit = static_cast<uint16_t>(e.bit_offset + (sub0_slot ? 16 : e.bit_length));
  desc.combined_access |= e.access;
  list.push_back(std::move(e));
  return list.back();
}

void Object::finalize() {
  image_.assign_zero((static_cast<size_t>(desc_->next_bit) + 7) / 8);
  load_defaults();
}

void Object::load_defaults() {
  std::memset(image_.data(), 0, image_.size());
  const std::vector<Entry>& entries = *desc_->entries;
  for (const Entry& e : entries) {
    if (e.default_value.empty()) {
      continue;
    }
    const size_t bits = std::min<size_t>(e.bit_length, e.default_value.size() * 8);
    if (e.bit_offset + bits > image_.size() * 8) {
      continue;
    }
    copy_bits(image_.data(), e.bit_offset, e.default_value.data(), 0, bits);
  }
  // An ARRAY/RECORD without a default for subindex 0 starts with all entries in use.
  if (code() != ObjectCode::Var && !entries.empty() && entries.front().subindex == 0 &&
      entries.front().default_value.empty() && !image_.empty()) {
    image_[0] = max_subindex();
  }
}

bool Object::set_default(uint8_t subindex, std::span<const uint8_t> value) {
  if (entry(subindex) == nullptr) return false;
  // The descriptions may be shared with identically described objects: copy them first.
  std::vector<Entry>& list = writable_entries();
  auto it = std::find_if(list.begin(), list.end(),
                         [subindex](const Entry& e) { return e.subindex == subindex; });
  it->default_value.assign(it->byte_length(), 0);
  std::copy_n(value.begin(), std::min(value.size(), it->default_value.size()),
              it->default_value.begin());
  return true;
}

const Entry* Object::entry(uint8_t subindex) const {
  const std::vector<Entry>& entries = *desc_->entries;
  if (subindex < entries.size() && entries[subindex].subindex == subindex) {
    return &entries[subindex];
  }
  auto it = std::lower_bound(entries.begin(), entries.end(), subindex,
                             [](const Entry& e, uint8_t s) { return e.subindex < s; });
  return (it != entries.end() && it->subindex == subindex) ? &*it : nullptr;
}

uint8_t Object::max_subindex() const {
  const std::vector<Entry>& entries = *desc_->entries;
  return entries.empty() ? 0 : entries.back().subindex;
}

uint8_t Object::sub0() const {
  if (code() == ObjectCode::Var || image_.empty()) {
    return 0;
  }
  return image_[0];
}

size_t Object::ca_end_bit(uint8_t last) const {
  size_t end = 0;
  for (const Entry& e : *desc_->entries) {
    if (e.subindex > last) {
      break;
    }
    const bool sub0_slot = code() != ObjectCode::Var && e.subindex == 0;
    end = std::max<size_t>(end, e.bit_offset + (sub0_slot ? 16u : e.bit_length));
  }
  return end;
}

std::span<uint8_t> Object::bytes(uint8_t subindex) {
  const Entry* e = entry(subindex);
  if (!e) {
    return {};
  }
  const size_t first = e->bit_offset / 8;
  if (first >= image_.size()) {
    return {};
  }
  const size_t len = std::min<size_t>(e->byte_length(), image_.size() - first);
  return image_.span().subspan(first, len);
}

std::span<const uint8_t> Object::bytes(uint8_t subindex) const {
  return const_cast<Object*>(this)->bytes(subindex);
}

uint64_t Object::get_u(uint8_t subindex) const {
  const Entry* e = entry(subindex);
  if (!e) {
    return 0;
  }
  uint8_t tmp[8] = {};
  const size_t bits = std::min<size_t>(e->bit_length, 64);
  if (e->bit_offset + bits > image_.size() * 8) {
    return 0;
  }
  copy_bits(tmp, 0, image_.data(), e->bit_offset, bits);
  return le::get(tmp, 8);
}

int64_t Object::get_i(uint8_t subindex) const {
  const Entry* e = entry(subindex);
  if (!e) {
    return 0;
  }
  const uint64_t u = get_u(subindex);
  const unsigned bits = std::min<unsigned>(e->bit_length, 64);
  if (bits == 64 || bits == 0) {
    return static_cast<int64_t>(u);
  }
  const uint64_t sign = uint64_t{1} << (bits - 1);
  return static_cast<int64_t>((u ^ sign) - sign);
}

void Object::set_u(uint8_t subindex, uint64_t value) {
  const Entry* e = entry(subindex);
  if (!e) {
    return;
  }
  uint8_t tmp[8];
  le::put(tmp, 8, value);
  const size_t bits = std::min<size_t>(e->bit_length, 64);
  if (e->bit_offset + bits > image_.size() * 8) {
    return;
  }
  copy_bits(image_.data(), e->bit_offset, tmp, 0, bits);
}

void Object::set_string(uint8_t subindex, std::string_view text) {
  auto b = bytes(subindex);
  std::fill(b.begin(), b.end(), 0);
  std::copy_n(text.begin(), std::min(text.size(), b.size()), b.begin());
}

std::string Object::get_string(uint8_t subindex) const {
  auto b = bytes(subindex);
  auto end = std::find(b.begin(), b.end(), uint8_t{0});
  return std::string(b.begin(), end);
}

ObjectDictionary::ObjectDictionary(const ObjectDictionary& other)
    : keys_(other.keys_), enums_(other.enums_) {
  objects_.reserve(other.objects_.size());
  for (const auto& o : other.objects_) objects_.push_back(std::make_unique<Object>(*o));
}

ObjectDictionary& ObjectDictionary::operator=(const ObjectDictionary& other) {
  if (this != &other) {
    ObjectDictionary copy(other);
    *this = std::move(copy);
  }
  return *this;
}

Object& ObjectDictionary::add(Object object) {
  const size_t pos = lower_bound(object.index());
  if (pos < keys_.size() && keys_[pos] == object.index()) {
    throw std::logic_error("object dictionary: index added twice: " +
                           std::to_string(object.index()));
  }
  if (object.image().size() < (object.ca_end_bit(255) + 7) / 8) {
    object.finalize();
  }
  object.share_entries();
  const uint16_t index = object.index();
  auto it = objects_.insert(objects_.begin() + static_cast<std::ptrdiff_t>(pos),
                            std::make_unique<Object>(std::move(object)));
  keys_.insert(keys_.begin() + static_cast<std::ptrdiff_t>(pos), index);
  return **it;
}

void ObjectDictionary::add_enum(EnumType type) {
  const uint16_t index = type.index;
  enums_.insert_or_assign(index, std::move(type));
}

bool ObjectDictionary::remove(uint16_t index) {
  const size_t pos = lower_bound(index);
  if (pos >= keys_.size() || keys_[pos] != index) {
    return false;
  }
  objects_.erase(objects_.begin() + static_cast<std::ptrdiff_t>(pos));
  keys_.erase(keys_.begin() + static_cast<std::ptrdiff_t>(pos));
  return true;
}

size_t ObjectDictionary::lower_bound(uint16_t index) const {
  return static_cast<size_t>(std::lower_bound(keys_.begin(), keys_.end(), index) - keys_.begin());
}

Object* ObjectDictionary::find(uint16_t index) {
  const size_t pos = lower_bound(index);
  return (pos < keys_.size() && keys_[pos] == index) ? objects_[pos].get() : nullptr;
}

const Object* ObjectDictionary::find(uint16_t index) const {
  return const_cast<ObjectDictionary*>(this)->find(index);
}

const EnumType* ObjectDictionary::find_enum(uint16_t index) const {
  auto it = enums_.find(index);
  return it == enums_.end() ? nullptr : &it->second;
}

size_t ObjectDictionary::max_image_bytes() const {
  size_t m = 0;
  for (const auto& o : objects_) {
    m = std::max(m, o->image().size());
  }
  return m;
}

}  // namespace rackcat::coe
