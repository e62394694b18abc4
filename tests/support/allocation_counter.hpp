// Allocation counting for the "nothing on the cyclic path allocates" tests, in one place:
// allocation_counter.cpp replaces the global operator new of the test binary that links it
// (target test_allocations) and counts the calls of the thread inside a
// CountAllocations scope. Other threads (UART, parameter worker) are not counted.
//
//   rackcat::testing::CountAllocations count;
//   ... the code under test ...
//   EXPECT_EQ(count.allocations(), 0u);
//
// Under AddressSanitizer operator new belongs to the sanitizer: available() is false and
// nothing is counted; the tests skip there (the sanitizer build checks memory errors).
#pragma once

#include <cstddef>

namespace rackcat::testing {

class CountAllocations {
 public:
  CountAllocations();   // starts counting on this thread from 0
  ~CountAllocations();  // stops counting
  CountAllocations(const CountAllocations&) = delete;
  CountAllocations& operator=(const CountAllocations&) = delete;

  // operator new calls of this thread since construction.
  size_t allocations() const;
  static bool available();
};

}  // namespace rackcat::testing
