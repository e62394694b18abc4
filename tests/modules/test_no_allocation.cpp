// The cyclic path allocates nothing: every driver, every kind of signal source and the
// exception-tree evaluation run for many cycles inside a CountAllocations scope
// (tests/support/allocation_counter.hpp).
#include <fstream>
#include <optional>

#include "modules/cards/analog_scale.hpp"
#include "tests/modules/rack_fixture.hpp"
#include "tests/support/allocation_counter.hpp"

using namespace rackcat;
using namespace rackcat::modules;
using namespace rackcat::modules::testing;

TEST_F(RackTest, CyclicPathAllocatesNothing) {
  if (!rackcat::testing::CountAllocations::available()) GTEST_SKIP() << "operator new is ASan's";
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

  std::optional<rackcat::testing::CountAllocations> count(std::in_place);
  for (int k = 0; k < 5000; ++k) {
    // Outputs change every cycle, so safe/unsafe wiring faults come and go, the exception
    // tree is re-evaluated and emergencies are queued.
    dout.set_u(1, static_cast<uint64_t>(k & 0xFFFF));
    // Channel diagnosis (0x10F3 messages and their Emergencies) appears and disappears.
    if (k % 100 == 0) {
      rack.set_sensor_open(tc, 1, (k / 100) % 2 == 0);
      rack.set_output_fault(at(1, 11).module().number, 3, (k / 100) % 3 == 0, false);
    }
    aout.set_u(1, AnalogScale{}.to_code((k % 200) / 20.0 - 5.0));
    clock += 0.001;
    rack.on_outputs(device);
    rack.before_inputs(device);
  }
  const size_t allocations = count->allocations();
  count.reset();
  EXPECT_EQ(allocations, 0u);
  EXPECT_NE(module_obj(at(1, 12), 0x6000, 0x2).get_u(1), 0u);
}
