// An allocator whose blocks start on a cache line (base::kCacheLine): an array of small per-cycle
// records then touches ceil(size / kCacheLine) lines instead of one more in most cases (issue 16:
// in a line of racks every line a slave's round touches misses again the next frame). For vectors
// built at start-up, never on the cyclic path.
#pragma once

#include <cstddef>
#include <new>
#include <vector>

#include "base/cache_line.hpp"

namespace rackcat::base {

template <class T>
struct CacheLineAllocator {
  using value_type = T;

  CacheLineAllocator() = default;
  template <class U>
  explicit CacheLineAllocator(const CacheLineAllocator<U>& /*other*/) noexcept {}

  T* allocate(size_t n) {
    return static_cast<T*>(::operator new (n * sizeof(T), std::align_val_t{kCacheLine}));
  }
  void deallocate(T* p, size_t /*n*/) noexcept {
    ::operator delete (p, std::align_val_t{kCacheLine});
  }
  friend bool operator==(const CacheLineAllocator&, const CacheLineAllocator&) { return true; }
};

// A vector whose elements start on a cache line.
template <class T>
using CacheLineVector = std::vector<T, CacheLineAllocator<T>>;

}  // namespace rackcat::base
