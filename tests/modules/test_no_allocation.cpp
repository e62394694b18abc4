// The cyclic path allocates nothing: every driver, every kind of signal source and the
// exception-tree evaluation run for many cycles with a counting global operator new.
#include <atomic>
#include <cstdlib>
#include <fstream>
#include <new>

#include "modules/cards/analog_scale.hpp"
#include "rack_fixture.hpp"

namespace {
std::atomic<bool> g_counting{false};
std::atomic<size_t> g_allocations{0};
}  // namespace

// AddressSanitizer owns operator new (all its variants, nothrow included); the sanitizer build
// checks memory errors, the regular build checks allocations. GCC says __SANITIZE_ADDRESS__,
// clang __has_feature(address_sanitizer).
#if defined(__SANITIZE_ADDRESS__)
#define RACKCAT_UNDER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define RACKCAT_UNDER_ASAN 1
#endif
#endif

#if defined(RACKCAT_UNDER_ASAN)
#define RACKCAT_COUNT_ALLOCATIONS 0
#else
#define RACKCAT_COUNT_ALLOCATIONS 1
// GCC cannot see that these replacements pair malloc with free.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void* operator new(std::size_t n) {
  if (g_counting.load(std::memory_order_relaxed)) g_allocations.fetch_add(1);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) {
  return operator new(n);
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete[](void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
  std::free(p);
}
#pragma GCC diagnostic pop
#endif

using namespace rackcat;
using namespace rackcat::modules;
using namespace rackcat::modules::testing;

TEST_F(RackTest, CyclicPathAllocatesNothing) {
  if (!RACKCAT_COUNT_ALLOCATIONS) GTEST_SKIP() << "operator new belongs to the sanitizer here";
  const std::string csv = ::testing::TempDir() + "noalloc.csv";
  std::ofstream(csv) << "0,0\n0.01,5\n0.02,-5\n";
  const uint16_t ain = at(1, 12).module().number;
  const uint16_t tc = at(1, 15).module().number;
  rack.set_source(ain, 1, "sine", {{"amplitude", "3"}, {"frequency", "7"}});
  rack.set_source(ain, 2, "noise", {{"stddev", "0.5"}, {"seed", "3"}});
  rack.set_source(ain, 3, "ramp", {{"from", "-1"}, {"to", "1"}, {"period_s", "0.1"}});
  rack.set_source(ain, 4, "replay", {{"file", csv}, {"loop", "true"}});
  rack.set_source(
      tc, 0, "plant",
      {{"plant", "oven"}, {"a", "-1 0; 1 -2"}, {"b", "1; 0"}, {"c", "0 1"}, {"inputs", "1.11.0"}});
  rack.set_wiring_fault(at(1, 1).module().number, 2, WiringFault::ShortToGround);
  to_op();
  coe::Object& dout = module_obj(at(1, 1), 0x7000, 0x0);
  coe::Object& aout = module_obj(at(1, 11), 0x7000, 0x2);
  for (int k = 0; k < 10; ++k) cycle();  // warm-up
  drain_emergencies();

  g_allocations = 0;
  g_counting = true;
  for (int k = 0; k < 5000; ++k) {
    // Outputs change every cycle, so safe/unsafe wiring faults come and go, the exception
    // tree is re-evaluated and emergencies are queued.
    dout.set_u(1, static_cast<uint64_t>(k & 0xFFFF));
    aout.set_u(1, AnalogScale{}.to_code((k % 200) / 20.0 - 5.0));
    clock += 0.001;
    rack.on_outputs(device);
    rack.before_inputs(device);
  }
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0u);
  EXPECT_NE(module_obj(at(1, 12), 0x6000, 0x2).get_u(1), 0u);
}
