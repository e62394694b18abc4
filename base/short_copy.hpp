// Copies of the few bytes a cyclic path moves (a slave's SyncManager buffer, one mapped PDO
// entry) without a library call: two fixed-size, possibly overlapping moves of the widest
// power of two not above the length; longer runs go to memcpy (issue 16). Compares of them
// (a device's repeated process data, mdp/repeated_cycles.hpp) the same way.
#pragma once

#include <cstdint>
#include <cstring>

namespace rackcat::base {

namespace detail {

// n bytes, width <= n <= 2 x width: the first and the last `width` bytes (they overlap when
// n < 2 x width), both loaded before either is stored.
template <typename Word>
inline void copy_overlapping(uint8_t* to, const uint8_t* from, uint64_t n) {
  Word a = 0;
  Word b = 0;
  std::memcpy(&a, from, sizeof(Word));
  std::memcpy(&b, from + n - sizeof(Word), sizeof(Word));
  std::memcpy(to, &a, sizeof(Word));
  std::memcpy(to + n - sizeof(Word), &b, sizeof(Word));
}

// n bytes, width <= n <= 2 x width, compared as the first and the last `width` bytes.
template <typename Word>
inline bool same_overlapping(const uint8_t* a, const uint8_t* b, uint64_t n) {
  Word a0 = 0;
  Word a1 = 0;
  Word b0 = 0;
  Word b1 = 0;
  std::memcpy(&a0, a, sizeof(Word));
  std::memcpy(&a1, a + n - sizeof(Word), sizeof(Word));
  std::memcpy(&b0, b, sizeof(Word));
  std::memcpy(&b1, b + n - sizeof(Word), sizeof(Word));
  return ((a0 ^ b0) | (a1 ^ b1)) == 0;
}

}  // namespace detail

inline void copy_bytes(uint8_t* to, const uint8_t* from, uint64_t n) {
  if (n >= 8 && n <= 16) {
    detail::copy_overlapping<uint64_t>(to, from, n);
  } else if (n >= 4 && n < 8) {
    detail::copy_overlapping<uint32_t>(to, from, n);
  } else if (n >= 2 && n < 4) {
    detail::copy_overlapping<uint16_t>(to, from, n);
  } else if (n == 1) {
    *to = *from;
  } else if (n > 16) {
    std::memcpy(to, from, n);
  }
}

// Whether the n bytes at a and b are equal.
inline bool same_bytes(const uint8_t* a, const uint8_t* b, uint64_t n) {
  if (n >= 8 && n <= 16) return detail::same_overlapping<uint64_t>(a, b, n);
  if (n >= 4 && n < 8) return detail::same_overlapping<uint32_t>(a, b, n);
  if (n >= 2 && n < 4) return detail::same_overlapping<uint16_t>(a, b, n);
  if (n == 1) return *a == *b;
  return n == 0 || std::memcmp(a, b, n) == 0;
}

}  // namespace rackcat::base
