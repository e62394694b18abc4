#include "coe/shared_entries.hpp"

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

struct Table {
  std::mutex mutex;
  std::unordered_multimap<uint64_t, std::weak_ptr<const std::vector<Entry>>> lists;
};

Table& table() {
  static auto* const t = new Table();  // NOLINT(cppcoreguidelines-owning-memory): never freed,
  return *t;                           // dictionaries may outlive static destruction order
}

}  // namespace

std::shared_ptr<const std::vector<Entry>> intern_entries(
    std::shared_ptr<const std::vector<Entry>> entries) {
  if (!entries || entries->empty()) return entries;
  const uint64_t key = hash_of(*entries);
  Table& t = table();
  std::lock_guard lock(t.mutex);
  auto [first, last] = t.lists.equal_range(key);
  for (auto it = first; it != last;) {
    if (auto shared = it->second.lock()) {
      if (shared == entries) return entries;  // interned already
      if (*shared == *entries) return shared;
      ++it;
    } else {
      it = t.lists.erase(it);  // no object uses it any more
    }
  }
  t.lists.emplace(key, entries);
  return entries;
}

}  // namespace rackcat::coe
