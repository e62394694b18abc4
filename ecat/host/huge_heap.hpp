// The heap of a long line in transparent huge pages.
//
// A line's per-slave state outside the ESCs (devices, dictionaries, drivers: about 40 KiB a
// tiny rack) is allocated once at start-up from malloc's main heap, in 4 KiB pages. Each cycle's
// round touches a few lines in several of those pages per slave, so at 1,024 slaves it needs
// far more page translations than the TLB holds (docs/PERFORMANCE.md, session 18: in process
// 100 -> 89-93 us a cycle, on the wire back to back 116-124 -> 105-117 us). Once the line is
// built, the heap's whole 2 MiB ranges are advised MADV_HUGEPAGE and collapsed into huge pages
// (MADV_COLLAPSE, Linux 6.1; older kernels leave the collapse to khugepaged). Contents do not
// change; the free holes inside those ranges become resident, which is why small lines (where
// measurements showed no gain) do not do it. The ESC address spaces stay in small pages
// (base/zero_pages.hpp: sparse by design).
#pragma once

#include <cstddef>

namespace rackcat::ecat {

struct HugeHeapResult {
  size_t advised_bytes = 0;  // heap bytes now advised MADV_HUGEPAGE (whole 2 MiB ranges)
  bool collapsed = false;    // MADV_COLLAPSE made them huge pages now
  int error = 0;             // errno of a refused MADV_HUGEPAGE (THP off, no [heap]), else 0
};

// Advises malloc's main heap (the [heap] mapping of /proc/self/maps) as above. Start-up only,
// after the line is built and before it runs: the collapse copies the heap (milliseconds for
// tens of MiB).
HugeHeapResult advise_huge_heap();

}  // namespace rackcat::ecat
