// The control module's mapping of heartbeat, NMT state, identity/card-list checks, bus errors
// and EMCY to the RIM states of 0x2rr1:08 (ONLINE / CONNECTED / OFFLINE / ERROR), alone and
// attached to a modules::Rack (latched bits, exception tree), on the virtual bus with the
// test's clock.
#include <gtest/gtest.h>

#include "modules/canopen/emcy.hpp"
#include "modules/canopen/virtual_bus.hpp"
#include "modules/rim/master.hpp"
#include "modules/rim/node.hpp"
#include "modules/rim/rack_link.hpp"
#include "modules/rim/threaded_link.hpp"
#include "rack_fixture.hpp"

using namespace rackcat;
using namespace rackcat::modules;
using namespace rackcat::modules::canopen;

namespace {

constexpr Micros kMs = 1'000;

class RimLink : public ::testing::Test {
 protected:
  RimLink()
      : rack(mdp::default_rack()),
        node_ep(bus.attach()),
        master_ep(bus.attach()),
        tool_ep(bus.attach()),
        master(rack, master_ep, options(), {2}) {
    master.on_state([this](uint8_t rim, RimState s, bool comm) {
      changes.push_back({rim, s, comm});
    });
  }
  static RimMasterOptions options() {
    RimMasterOptions o;
    o.heartbeat_timeout_us = 150 * kMs;
    return o;
  }
  void start_node() {
    node = std::make_unique<RimNode>(rack, 2, node_ep);
    node->start(now);
  }
  void run_for(Micros d) {
    for (Micros end = now + d; now < end;) {
      now += kMs;
      if (node) node->step(now);
      master.step(now);
      CanFrame f;
      while (tool_ep.receive(f)) {
      }
    }
  }
  struct Change {
    uint8_t rim;
    RimState state;
    bool comm_error;
  };

  mdp::RackConfig rack;
  VirtualCanBus bus;
  VirtualCanBus::Endpoint& node_ep;
  VirtualCanBus::Endpoint& master_ep;
  VirtualCanBus::Endpoint& tool_ep;
  RimMaster master;
  std::unique_ptr<RimNode> node;
  std::vector<Change> changes;
  Micros now = 0;
};

}  // namespace

TEST_F(RimLink, BootCheckStartOnline) {
  EXPECT_EQ(master.state(2), RimState::Offline);
  start_node();
  run_for(100 * kMs);
  EXPECT_EQ(node->state(), NmtState::Operational);
  ASSERT_EQ(master.state(2), RimState::Online) << master.reason(2);
  ASSERT_FALSE(changes.empty());
  EXPECT_EQ(changes.back().state, RimState::Online);
  EXPECT_GE(master.last_input_time(2), 0);
}

TEST_F(RimLink, HeartbeatLossIsOfflineWithinTheConsumerTimeAndRestartIsOnline) {
  start_node();
  run_for(100 * kMs);
  ASSERT_EQ(master.state(2), RimState::Online);
  // Unplug: the RIM process is gone.
  node.reset();
  node_ep.set_connected(false);
  const Micros killed = now;
  while (master.state(2) == RimState::Online && now < killed + kMs * 1000) run_for(kMs);
  EXPECT_EQ(master.state(2), RimState::Offline);
  // Last heartbeat at most one producer period (50 ms) before the kill, consumer time 150 ms.
  EXPECT_LE(now - killed, 150 * kMs + kMs);
  EXPECT_TRUE(changes.back().comm_error);  // lost through a communication error
  // Replug: boot-up, check, start.
  node_ep.set_connected(true);
  start_node();
  run_for(100 * kMs);
  EXPECT_EQ(master.state(2), RimState::Online) << master.reason(2);
}

TEST_F(RimLink, PreOperationalIsConnectedNotOnline) {
  start_node();
  run_for(100 * kMs);
  ASSERT_EQ(master.state(2), RimState::Online);
  tool_ep.send(nmt_frame(NmtCommand::EnterPreOperational, 2));
  run_for(100 * kMs);
  EXPECT_EQ(node->state(), NmtState::PreOperational);
  EXPECT_EQ(master.state(2), RimState::Connected);
  // A reset makes it boot again: checked and started anew.
  tool_ep.send(nmt_frame(NmtCommand::ResetNode, 2));
  run_for(100 * kMs);
  EXPECT_EQ(master.state(2), RimState::Online);
}

TEST_F(RimLink, CardListMismatchIsConnectedAndNeverStarted) {
  // The RIM on node-ID 2 has different cards than the rack file says.
  auto other = mdp::parse_rack_config(R"(
rims:
  - rim: 2
    type: 12-slot
    part_number: FI-RM1200-00
    serial_number: FI-RM1200-00-0001
    slots:
      - {slot: 1, card: CDI-10}
)",
                                      "other.yaml");
  node = std::make_unique<RimNode>(other, 2, node_ep);
  node->start(now);
  run_for(200 * kMs);
  EXPECT_EQ(master.state(2), RimState::Connected);
  EXPECT_EQ(node->state(), NmtState::PreOperational);
  EXPECT_NE(master.reason(2).find("card list mismatch"), std::string::npos) << master.reason(2);
}

TEST_F(RimLink, RepeatedSdoTimeoutsAreError) {
  // Something on node-ID 2 sends heartbeats but answers no SDO.
  for (int i = 0; i < 100 && master.state(2) != RimState::Error; ++i) {
    node_ep.send(heartbeat_frame(2, NmtState::PreOperational));
    run_for(20 * kMs);
  }
  EXPECT_EQ(master.state(2), RimState::Error);
  EXPECT_NE(master.reason(2).find("SDO timeout"), std::string::npos) << master.reason(2);
}

TEST_F(RimLink, BusOffAndErrorPassiveAreError) {
  start_node();
  run_for(100 * kMs);
  master_ep.set_error_state(false, true);
  run_for(kMs);
  EXPECT_EQ(master.state(2), RimState::Error);
  master_ep.set_error_state(false, false);
  run_for(kMs);
  EXPECT_EQ(master.state(2), RimState::Online);
  master_ep.set_error_state(true, false);
  run_for(kMs);
  EXPECT_EQ(master.state(2), RimState::Error);
}

TEST_F(RimLink, CommunicationEmcyIsErrorUntilErrorReset) {
  start_node();
  run_for(100 * kMs);
  node->emergency({0x8120, 0x11, {}});  // CAN in error passive mode
  run_for(2 * kMs);
  EXPECT_EQ(master.state(2), RimState::Error);
  node->emergency({0x0000, 0x00, {}});
  run_for(2 * kMs);
  EXPECT_EQ(master.state(2), RimState::Online);
}

// Attached to the emulated rack: the RIM state, latched bits and exception tree follow the
// CAN link, inputs come from the RIM's TPDOs, and a fan EMCY sets the RIM's fan bits.
class RimLinkRack : public rackcat::modules::testing::RackTest {
 protected:
  RimLinkRack()
      : node_ep(bus.attach()),
        master_ep(bus.attach()),
        master(device.config(), master_ep, RimMasterOptions{}, {2}) {
    attach_rim_master(master, rack);
  }
  void run_for(Micros d) {
    for (Micros end = now + d; now < end;) {
      now += kMs;
      if (node) node->step(now);
      master.step(now);
      cycle();
    }
  }
  VirtualCanBus bus;
  VirtualCanBus::Endpoint& node_ep;
  VirtualCanBus::Endpoint& master_ep;
  RimMaster master;
  std::unique_ptr<RimNode> node;
  Micros now = 0;
};

TEST_F(RimLinkRack, RimStateAndInputsFollowTheCanLink) {
  to_op();
  EXPECT_EQ(obj(0x2021).get_u(8) & 3u, 0u);  // OFFLINE until the heartbeat comes
  node = std::make_unique<RimNode>(device.config(), 2, node_ep);
  node->set_source(1, 5, std::make_unique<ConstantSource>(1.0));  // CDI-13 channel 5
  node->start(now);
  run_for(100 * kMs);
  EXPECT_EQ(obj(0x2021).get_u(8) & 3u, 2u);  // ONLINE
  EXPECT_EQ(at(2, 1).inputs()[5].value, 1.0);
  drain_emergencies();

  node.reset();
  node_ep.set_connected(false);
  run_for(300 * kMs);
  // OFFLINE (0), latched state error (bit 3) and communication error (bit 4).
  EXPECT_EQ(obj(0x2021).get_u(8) & 0x1Bu, 0x18u);
  EXPECT_EQ(obj(0xF388).get_u(1), 1u << 2);
  EXPECT_TRUE(has_code(drain_emergencies(), 0xA001));
  EXPECT_EQ(*master.input_ptr(2, 1, 5), 0.0);  // stale values are not kept
}

TEST_F(RimLinkRack, FanEmcySetsTheRimFanEventBits) {
  node = std::make_unique<RimNode>(device.config(), 2, node_ep);
  node->start(now);
  run_for(100 * kMs);
  // Slot-card fan at 1000 RPM of 3000 nominal: -67 % -> warning, error and failure bits.
  node->emergency({emcy::kFan, 0x81, {1, 0xE8, 0x03, 0, 0}});
  run_for(2 * kMs);
  rack.refresh();
  const uint64_t bits = obj(0x2021).get_u(8);
  EXPECT_TRUE(bits & rim_event::kSlotFanWarning);
  EXPECT_TRUE(bits & rim_event::kSlotFanError);
  EXPECT_TRUE(bits & rim_event::kSlotFanFailure);
}

// The link `rackcat run --rim-bus can:IFACE` uses, driven without its thread: inputs and
// outputs cross through the mirrors, state changes through the post function.
namespace {
class ForwardingBus final : public CanBus {
 public:
  explicit ForwardingBus(CanBus& to) : to_(to) {}
  bool send(const CanFrame& f) override { return to_.send(f); }
  bool receive(CanFrame& f) override { return to_.receive(f); }
  void wait(Micros us) override { to_.wait(us); }
  const BusStatus& status() const override { return to_.status(); }

 private:
  CanBus& to_;
};
}  // namespace

TEST_F(RimLinkRack, ThreadedLinkCarriesInputsOutputsAndStates) {
  master_ep.set_connected(false);  // the fixture's master stays out of this test
  auto& link_ep = bus.attach();
  std::vector<std::function<void()>> posted;
  ThreadedRimLink link(
      rack, std::make_unique<ForwardingBus>(link_ep), RimMasterOptions{}, {2},
      [&](std::function<void()> f) { posted.push_back(std::move(f)); },
      /*start_thread=*/false);
  EXPECT_EQ(obj(0x2021).get_u(8) & 3u, 0u);  // OFFLINE until the heartbeat comes
  node = std::make_unique<RimNode>(device.config(), 2, node_ep);
  node->set_source(3, 4, std::make_unique<ConstantSource>(1.0));  // CDI-10/X8 channel 4
  node->start(now);
  to_op();
  // One millisecond of RIM, link thread, posted state changes and device cycle.
  auto run_ms = [&](int ms) {
    for (int i = 0; i < ms; ++i) {
      now += kMs;
      node->step(now);
      link.poll(now);
      for (auto& f : posted) f();
      posted.clear();
      cycle();
    }
  };
  run_ms(100);
  EXPECT_EQ(link.master().state(2), RimState::Online) << link.master().reason(2);
  EXPECT_EQ(obj(0x2021).get_u(8) & 3u, 2u);
  EXPECT_EQ(at(2, 3).inputs()[4].value, 1.0);
  EXPECT_EQ(at(2, 3).inputs()[3].value, 0.0);
  // An output driven in the rack reaches the RIM: drive CDO-10 (slot 7) channel 2 through
  // its 0x7nn0 object as the master's output data would.
  CardDriver& dout = at(2, 7);
  module_obj(dout, 0x7000, 0).set_u(1, 1u << 2);
  run_ms(10);
  EXPECT_EQ(dout.outputs()[2].driven, 1.0);
  EXPECT_EQ(node->output(7, 2), 1.0);
  EXPECT_EQ(node->output(7, 3), 0.0);
}

TEST_F(RimLink, RimThatLosesTheControlModuleDeEnergisesItsOutputs) {
  double on = 1.0;
  ASSERT_TRUE(master.bind_output(2, 7, 0, &on));  // CDO-10 in slot 7 of RIM 2
  start_node();
  run_for(100 * kMs);
  ASSERT_EQ(master.state(2), RimState::Online);
  EXPECT_EQ(node->output(7, 0), 1.0);
  // The control module stops (its heartbeat, 0x77F, and its RPDOs end).
  master_ep.set_connected(false);
  for (int i = 0; i < 600; ++i) node->step(now += kMs);
  EXPECT_EQ(node->output(7, 0), 0.0);
  EXPECT_EQ(node->state(), NmtState::PreOperational);
  EXPECT_EQ(node->counters().control_module_losses, 1u);
  bool emcy = false;
  for (const CanFrame& f : bus.log()) {
    if (f.id == 0x082 && f.data[0] == 0x30 && f.data[1] == 0x81) emcy = true;  // 0x8130
  }
  EXPECT_TRUE(emcy);
  EXPECT_EQ(node->dictionary().find(0x1016)->get_u(1), (0x7Fu << 16) | 500u);
}
