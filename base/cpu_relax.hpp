// A hint to the CPU inside a spin-wait: the loop is waiting on memory another agent (the
// kernel filling the receive ring) writes, so the core may save power and leave its
// sibling thread the pipeline, and leaves the loop without the memory-order mis-speculation
// a plain spin pays when the value finally changes (Intel SDM, PAUSE; Arm ARM, YIELD).
#pragma once

namespace rackcat::base {

inline void cpu_relax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#elif defined(__aarch64__) || defined(__arm__)
  asm volatile("yield" ::: "memory");
#endif
}

}  // namespace rackcat::base
