// The cache line size rackcat lays hot state out for: 64 bytes on the x86-64 and AArch64
// machines it runs on. Named once so alignment and allocation agree (issue 16: at 199 slaves
// every line a slave's round touches misses again the next frame).
#pragma once

#include <cstddef>

namespace rackcat::base {

inline constexpr size_t kCacheLine = 64;

}  // namespace rackcat::base
