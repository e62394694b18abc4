// The cyclic path of the device: SM2 bytes land in the mapped 0x7nnX entries, 0x6nnX entries
// come out in SM3 at the positions the PDO assignment gives, listeners run in order around the
// copies, and the ESM hooks reach them.
#include <gtest/gtest.h>

#include "mdp/device.hpp"
#include "mdp/sync_manager_layout.hpp"

namespace rackcat::mdp {
namespace {

// A rack with a known layout: DOUTx16 (module 1), DINx16 (2), AOUTx8 (3), DOUTx4+DINx4 (4).
const char* kRack = R"(rims:
  - rim: 1
    type: 6-slot
    slots:
      - {slot: 1, card: CDO-10}
      - {slot: 2, card: CDI-10}
      - {slot: 3, card: CAO-15}
      - {slot: 4, card: CRS-14}
)";

struct Recorder : CycleListener {
  std::vector<std::string> calls;
  uint16_t seen_dout = 0;
  void on_outputs(Device& d) override {
    calls.push_back("outputs");
    seen_dout = static_cast<uint16_t>(d.dictionary().find(0x7000)->get_u(1));
  }
  void before_inputs(Device& d) override {
    calls.push_back("inputs");
    // A driver: the DIN card reads what the DOUT card drives (loopback).
    d.dictionary().find(0x6010)->set_u(1, d.dictionary().find(0x7000)->get_u(1));
    d.dictionary().find(0x6030 + 0xB)->set_u(1, 0xA);
  }
  void on_state_changed(Device&, EsmState from, EsmState to) override {
    calls.push_back("state " + std::to_string(int(from)) + "->" + std::to_string(int(to)));
  }
  void on_sync(Device&, int which, uint64_t) override {
    calls.push_back("sync" + std::to_string(which));
  }
  void on_watchdog_expired(Device&) override { calls.push_back("watchdog"); }
};

class Cyclic : public ::testing::Test {
 protected:
  void SetUp() override {
    DeviceOptions opt;
    opt.load_stored_parameters = false;
    opt.state_dir = ::testing::TempDir() + "/mdp_cyclic";
    device = std::make_unique<Device>(parse_rack_config(kRack, "rack.yaml"), opt);
    device->add_listener(&rec);
  }
  Recorder rec;
  std::unique_ptr<Device> device;
};

TEST_F(Cyclic, ProcessImageSizesFollowTheAssignment) {
  // Outputs: DOUTx16 (2) + AOUTx8 (16) + DOUTx4 with pad (1) = 19 bytes.
  EXPECT_EQ(device->output_bytes(), 19);
  // Inputs: DINx16 (2) + DINx4 with pad (1) = 3 bytes.
  EXPECT_EQ(device->input_bytes(), 3);
}

TEST_F(Cyclic, OutputsReachObjectsAndInputsLeaveThemAtTheirOffsets) {
  std::vector<uint8_t> sm2(19, 0);
  sm2[0] = 0x34;  // 0x7000:01 = 0x1234
  sm2[1] = 0x12;
  sm2[2] = 0xCD;  // 0x7022:01 = 0xABCD
  sm2[3] = 0xAB;
  sm2[18] = 0xF5;  // 0x703B:01 = 5 (4 bits), the pad bits are ignored
  device->write_outputs(sm2);
  const auto& od = device->dictionary();
  EXPECT_EQ(od.find(0x7000)->get_u(1), 0x1234u);
  EXPECT_EQ(od.find(0x7022)->get_u(1), 0xABCDu);
  EXPECT_EQ(od.find(0x703B)->get_u(1), 0x5u);
  EXPECT_EQ(rec.seen_dout, 0x1234);  // the listener ran after the copy

  std::vector<uint8_t> sm3(3, 0xFF);
  device->read_inputs(sm3);
  EXPECT_EQ(sm3, (std::vector<uint8_t>{0x34, 0x12, 0x0A}));  // pad bits read 0
  EXPECT_EQ(rec.calls, (std::vector<std::string>{"outputs", "inputs"}));
}

TEST_F(Cyclic, StateSyncAndWatchdogEventsReachListeners) {
  ASSERT_EQ(device->request_state(EsmState::Init, EsmState::PreOp), 0);
  device->state_changed(EsmState::Init, EsmState::PreOp);
  EXPECT_EQ(device->state(), EsmState::PreOp);
  device->sync_event(0, 1000);
  device->watchdog_expired();
  device->remove_listener(&rec);
  device->sync_event(0, 2000);
  EXPECT_EQ(rec.calls, (std::vector<std::string>{"state 1->2", "sync0", "watchdog"}));
}

TEST_F(Cyclic, AnEventsOnlyListenerHearsEverythingButTheCycle) {
  Recorder events;
  device->add_listener(&events, Device::ListenerScope::EventsOnly);
  device->state_changed(EsmState::Init, EsmState::PreOp);
  std::vector<uint8_t> sm2(device->output_bytes(), 0);
  std::vector<uint8_t> sm3(device->input_bytes(), 0);
  device->write_outputs(sm2);
  device->read_inputs(sm3);
  device->sync_event(0, 1000);
  device->watchdog_expired();
  EXPECT_EQ(events.calls, (std::vector<std::string>{"state 1->2", "watchdog"}));
  // The other listener still hears the cyclic callbacks, in order.
  EXPECT_EQ(rec.calls,
            (std::vector<std::string>{"state 1->2", "outputs", "inputs", "sync0", "watchdog"}));
  device->remove_listener(&events);
  device->state_changed(EsmState::PreOp, EsmState::Init);
  EXPECT_EQ(events.calls.size(), 2u);
}

TEST_F(Cyclic, InputLatchTimestampsFollowTheInputUpdate) {
  device->sync_event(0, 123456789);
  std::vector<uint8_t> sm3(3);
  device->read_inputs(sm3);
  const auto* esc = device->dictionary().find(0xF6F2);
  for (uint8_t s = 1; s <= esc->sub0(); ++s) EXPECT_EQ(esc->get_u(s), 123456789u);
  // Rounds without a new SYNC0 keep it; the next SYNC0's time is there after the next update.
  device->read_inputs(sm3);
  for (uint8_t s = 1; s <= esc->sub0(); ++s) EXPECT_EQ(esc->get_u(s), 123456789u);
  device->sync_event(0, 223456789);
  for (uint8_t s = 1; s <= esc->sub0(); ++s) EXPECT_EQ(esc->get_u(s), 123456789u);
  device->read_inputs(sm3);
  for (uint8_t s = 1; s <= esc->sub0(); ++s) EXPECT_EQ(esc->get_u(s), 223456789u);
}

TEST_F(Cyclic, ModuleObjectIndicesFollowTheNumberingRule) {
  const auto mods = device->modules();
  ASSERT_EQ(mods.size(), 4u);
  EXPECT_EQ(mods[2].index(0x7000, 2), 0x7022);
  EXPECT_EQ(mods[3].index(0x6000, 0xB), 0x603B);
  EXPECT_EQ(mods[3].index(0x4000, 1), 0x4031);
  EXPECT_EQ(sm::rx_pdo_index(mods[3].number), 0x1603);
  EXPECT_EQ(sm::tx_pdo_index(mods[1].number), 0x1A01);
}

}  // namespace
}  // namespace rackcat::mdp
