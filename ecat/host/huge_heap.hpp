// The heap of a long line: grown in huge-page steps while it is built, then in transparent huge
// pages.
//
// A line's per-slave state outside the ESCs (devices, dictionaries, drivers: about 40 KiB a
// tiny rack) is allocated once at start-up from malloc's main heap, in 4 KiB pages. Each cycle's
// round touches a few lines in several of those pages per slave, so at 1,024 slaves it needs
// far more page translations than the TLB holds (docs/PERFORMANCE.md, session 18: in process
// 100 -> 89-93 us a cycle, on the wire back to back 116-124 -> 105-117 us; 0-5 % on the wire
// once the heap grows in 2 MiB steps, session 19, grow_heap_in_huge_page_steps). Once the line is
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

// Makes malloc grow (and trim) its main heap in steps of 2 MiB rather than its default 128 KiB
// (mallopt M_TOP_PAD). Start-up only, before the line is built. Measured, not derived: with it a
// back-to-back cycle of 1,024 tiny racks configured by ethercrab takes 86-92 us on the wire
// instead of 122-131 us, the same with transparent huge pages disabled for the process, and set
// after the line is built it changes nothing; so it is the line's layout in the heap, not the
// pages under it. Not fast bins (M_MXFAST 0 left it slow), not trimming (a trim threshold of
// 1 GB left it slow); small lines and the in-process benchmarks show no change either way
// (docs/PERFORMANCE.md, session 19). RSS stays the same: the top's untouched pages are not
// resident. False where the C library has no such option (not glibc) or refuses it.
bool grow_heap_in_huge_page_steps();

}  // namespace rackcat::ecat
