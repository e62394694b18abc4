// The cyclic path allocates nothing: every driver, every kind of signal source and the
// exception-tree evaluation run for many cycles inside a CountAllocations scope
// (tests/support/allocation_counter.hpp).
#include <fstream>
#include <optional>
#include <vector>

#include "base/round_time.hpp"
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

// A `ctl` output-fault injection runs on the device thread: watching a module's outputs from
// then on must not allocate either, whichever module is the first (or the last) to get one.
TEST_F(RackTest, OutputFaultInjectionAllocatesNothing) {
  if (!rackcat::testing::CountAllocations::available()) GTEST_SKIP() << "operator new is ASan's";
  to_op();
  cycle();
  drain_emergencies();
  std::vector<uint16_t> with_outputs;
  for (uint16_t m = 1; rack.driver(m) != nullptr; ++m) {
    if (!rack.driver(m)->outputs().empty()) with_outputs.push_back(m);
  }
  ASSERT_GT(with_outputs.size(), 1u);
  std::optional<rackcat::testing::CountAllocations> count(std::in_place);
  for (const uint16_t m : with_outputs) rack.set_output_fault(m, 0, true, false);
  const size_t allocations = count->allocations();
  count.reset();
  EXPECT_EQ(allocations, 0u);
  cycle();
  EXPECT_FALSE(drain_emergencies().empty());  // the injected overloads are reported
}

// The whole device path a frame takes: SM2 bytes through the process image into
// the objects and the drivers, then the drivers, the input latch times (0xF6F0/0xF6F2) and the
// process image back into SM3 bytes - with the entry descriptions shared with a second device
// of the same rack (coe/shared_entries.hpp) and the file commands on the shared worker.
TEST_F(RackTest, DeviceProcessDataPathAllocatesNothing) {
  if (!rackcat::testing::CountAllocations::available()) GTEST_SKIP() << "operator new is ASan's";
  mdp::DeviceOptions options;
  options.state_dir = ::testing::TempDir() + "noalloc_second_device";
  options.load_stored_parameters = false;
  mdp::Device twin(mdp::default_rack(), options);
  const coe::Object* latch = device.dictionary().find(0xF6F0);
  ASSERT_NE(latch, nullptr);
  EXPECT_EQ(latch->entries().data(), twin.dictionary().find(0xF6F0)->entries().data());
  to_op();
  std::vector<uint8_t> outputs(device.output_bytes(), 0);
  std::vector<uint8_t> inputs(device.input_bytes(), 0);
  ASSERT_FALSE(outputs.empty());
  ASSERT_FALSE(inputs.empty());
  for (int k = 0; k < 10; ++k) {  // warm-up
    clock += 0.001;
    device.write_outputs(outputs);
    device.read_inputs(inputs);
  }
  drain_emergencies();
  std::optional<rackcat::testing::CountAllocations> count(std::in_place);
  for (int k = 0; k < 5000; ++k) {
    outputs[static_cast<size_t>(k) % outputs.size()] = static_cast<uint8_t>(k);
    clock += 0.001;
    // Every other cycle inside a firmware round (base/round_time.hpp), as Segment::after_frame
    // runs it: the latch time then comes from the round.
    std::optional<base::RoundTime::Scope> round;
    if (k % 2 == 0) round.emplace();
    device.write_outputs(outputs);
    device.read_inputs(inputs);
  }
  const size_t allocations = count->allocations();
  count.reset();
  EXPECT_EQ(allocations, 0u);
}
