#include "coe/shared_entries.hpp"

#include <cstdint>
#include <mutex>
#include <string_view>
#include <unordered_map>

namespace rackcat::coe {
namespace {

// FNV-1a over every field operator== compares.
struct Hasher {
  uint64_t h = 1469598103934665603ull;
  void bytes(const void* p, size_t n) {
    const auto* b = static_cast<const uint8_t*>(p);
    for (size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ull;
  }
  template <typename T>
  void value(const T& v) {
    bytes(&v, sizeof v);
  }
  void text(std::string_view s) {
    value(s.size());
    bytes(s.data(), s.size());
  }
};

uint64_t hash_of(const std::vector<Entry>& entries) {
  Hasher h;
  h.value(entries.size());
  for (const Entry& e : entries) {
    h.value(e.subindex);
    h.text(e.name);
    h.value(e.data_type);
    h.value(e.bit_length);
    h.value(e.bit_offset);
    h.value(e.access);
    h.value(e.default_value.size());
    if (!e.default_value.empty()) h.bytes(e.default_value.data(), e.default_value.size());
    h.value(e.min.value_or(0x5A5A5A5A5A5A5A5All));
    h.value(e.max.value_or(0x5A5A5A5A5A5A5A5All));
    h.value(e.padding);
    h.value(e.unit);
    h.value(e.max_of);
    h.value(e.min_of);
    h.value(e.unit_type);
  }
  return h.h;
}

// Descriptions are equal when every field is, the entry lists by identity (both interned).
bool same(const ObjectDescription& a, const ObjectDescription& b) {
  return a.name == b.name && a.entries == b.entries && a.data_type == b.data_type &&
         a.combined_access == b.combined_access && a.next_bit == b.next_bit && a.code == b.code &&
         a.packed == b.packed;
}
bool same(const std::vector<Entry>& a, const std::vector<Entry>& b) {
  return a == b;
}

uint64_t hash_of(const ObjectDescription& d) {
  Hasher h;
  h.text(d.name);
  h.value(reinterpret_cast<uintptr_t>(d.entries.get()));  // interned: identity is equality
  h.value(d.data_type);
  h.value(d.combined_access);
  h.value(d.next_bit);
  h.value(d.code);
  h.value(d.packed);
  return h.h;
}

template <typename T>
struct Table {
  std::mutex mutex;
  std::unordered_multimap<uint64_t, std::weak_ptr<const T>> items;

  std::shared_ptr<const T> intern(std::shared_ptr<const T> item) {
    const uint64_t key = hash_of(*item);
    std::lock_guard lock(mutex);
    auto [first, last] = items.equal_range(key);
    for (auto it = first; it != last;) {
      if (auto shared = it->second.lock()) {
        if (shared == item) return item;  // interned already
        if (same(*shared, *item)) return shared;
        ++it;
      } else {
        it = items.erase(it);  // no object uses it any more
      }
    }
    items.emplace(key, item);
    return item;
  }
};

template <typename T>
Table<T>& table() {
  static auto* const t = new Table<T>();  // NOLINT(cppcoreguidelines-owning-memory): never
  return *t;  // freed, dictionaries may outlive static destruction order
}

}  // namespace

std::shared_ptr<const std::vector<Entry>> intern_entries(
    std::shared_ptr<const std::vector<Entry>> entries) {
  if (!entries || entries->empty()) return entries;
  return table<std::vector<Entry>>().intern(std::move(entries));
}

std::shared_ptr<const ObjectDescription> intern_description(
    std::shared_ptr<const ObjectDescription> desc) {
  if (!desc) return desc;
  auto entries = intern_entries(desc->entries);
  if (entries != desc->entries) {
    auto copy = std::make_shared<ObjectDescription>(*desc);
    copy->entries = std::move(entries);
    desc = std::move(copy);
  }
  return table<ObjectDescription>().intern(std::move(desc));
}

}  // namespace rackcat::coe
