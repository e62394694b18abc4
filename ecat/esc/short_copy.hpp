// Copies of the few bytes of process data a slave has (a few bytes per SyncManager buffer)
// without a library call: two fixed-size, possibly overlapping moves; longer runs go to memcpy.
#pragma once

#include <cstdint>
#include <cstring>

namespace rackcat::ecat {

inline void copy_bytes(uint8_t* to, const uint8_t* from, uint64_t n) {
  if (n >= 8 && n <= 16) {
    uint64_t a = 0;
    uint64_t b = 0;
    std::memcpy(&a, from, 8);
    std::memcpy(&b, from + n - 8, 8);
    std::memcpy(to, &a, 8);
    std::memcpy(to + n - 8, &b, 8);
  } else if (n >= 4 && n < 8) {
    uint32_t a = 0;
    uint32_t b = 0;
    std::memcpy(&a, from, 4);
    std::memcpy(&b, from + n - 4, 4);
    std::memcpy(to, &a, 4);
    std::memcpy(to + n - 4, &b, 4);
  } else if (n >= 2 && n < 4) {
    uint16_t a = 0;
    uint16_t b = 0;
    std::memcpy(&a, from, 2);
    std::memcpy(&b, from + n - 2, 2);
    std::memcpy(to, &a, 2);
    std::memcpy(to + n - 2, &b, 2);
  } else if (n == 1) {
    *to = *from;
  } else if (n > 16) {
    std::memcpy(to, from, n);
  }
}

}  // namespace rackcat::ecat
