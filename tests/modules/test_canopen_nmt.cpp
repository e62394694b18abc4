// CANopen NMT slave state machine, NMT command and heartbeat frames (CiA 301 §7.2.8.3,
// Tables 52/53) and the heartbeat consumer, on the deterministic virtual bus.
#include <gtest/gtest.h>

#include "modules/canopen/nmt.hpp"
#include "modules/canopen/socketcan.hpp"
#include "modules/canopen/virtual_bus.hpp"

using namespace rackcat::modules::canopen;

TEST(CanopenNmt, CommandAndHeartbeatFramesAreCia301Layouts) {
  // NMT "start remote node" to node 5: COB-ID 0, bytes 01 05.
  const CanFrame start = nmt_frame(NmtCommand::Start, 5);
  EXPECT_EQ(start.id, 0x000u);
  ASSERT_EQ(start.len, 2);
  EXPECT_EQ(start.data[0], 0x01);
  EXPECT_EQ(start.data[1], 0x05);
  // Reset communication of all nodes: 82 00.
  const CanFrame reset = nmt_frame(NmtCommand::ResetCommunication, 0);
  EXPECT_EQ(reset.data[0], 0x82);
  EXPECT_EQ(reset.data[1], 0x00);
  // Heartbeat of node 3 in OPERATIONAL: COB-ID 0x703, one byte 05; PRE-OPERATIONAL 7F.
  const CanFrame hb = heartbeat_frame(3, NmtState::Operational);
  EXPECT_EQ(hb.id, 0x703u);
  ASSERT_EQ(hb.len, 1);
  EXPECT_EQ(hb.data[0], 0x05);
  EXPECT_EQ(heartbeat_frame(3, NmtState::PreOperational).data[0], 0x7F);
}

TEST(CanopenNmt, SlaveBootsIntoPreOperationalAndFollowsCommands) {
  NmtSlave nmt(2);
  const CanFrame boot = nmt.boot();
  EXPECT_EQ(boot.id, 0x702u);  // boot-up message: heartbeat COB-ID, state 0
  EXPECT_EQ(boot.data[0], 0x00);
  EXPECT_EQ(nmt.state(), NmtState::PreOperational);

  EXPECT_EQ(nmt.on_frame(nmt_frame(NmtCommand::Start, 2)), NmtSlave::Reset::None);
  EXPECT_EQ(nmt.state(), NmtState::Operational);
  nmt.on_frame(nmt_frame(NmtCommand::Stop, 3));  // another node: ignored
  EXPECT_EQ(nmt.state(), NmtState::Operational);
  nmt.on_frame(nmt_frame(NmtCommand::Stop, 0));  // broadcast
  EXPECT_EQ(nmt.state(), NmtState::Stopped);
  nmt.on_frame(nmt_frame(NmtCommand::EnterPreOperational, 2));
  EXPECT_EQ(nmt.state(), NmtState::PreOperational);
  EXPECT_EQ(nmt.on_frame(nmt_frame(NmtCommand::ResetNode, 2)), NmtSlave::Reset::Node);
  EXPECT_EQ(nmt.on_frame(nmt_frame(NmtCommand::ResetCommunication, 2)),
            NmtSlave::Reset::Communication);
  nmt.boot();
  // An unknown command specifier or a frame of the wrong length changes nothing.
  const uint8_t bad[2] = {0x55, 2};
  nmt.on_frame(CanFrame::make(0, bad));
  const uint8_t short_frame[1] = {0x01};
  nmt.on_frame(CanFrame::make(0, short_frame));
  EXPECT_EQ(nmt.state(), NmtState::PreOperational);
}

TEST(CanopenNmt, ProducerSendsOnePerPeriod) {
  HeartbeatProducer p(100'000);
  p.restart(0);
  CanFrame f;
  int sent = 0;
  for (Micros t = 0; t <= 1'000'000; t += 1'000) {
    if (p.poll(t, 4, NmtState::Operational, f)) ++sent;
  }
  EXPECT_EQ(sent, 10);
  EXPECT_EQ(f.id, 0x704u);
}

TEST(CanopenNmt, ConsumerLosesANodeWhoseHeartbeatStops) {
  HeartbeatConsumer c;
  c.watch(1, 150'000);
  EXPECT_EQ(c.on_frame(heartbeat_frame(1, NmtState::BootUp), 0), HeartbeatConsumer::Event::BootUp);
  EXPECT_TRUE(c.node(1)->alive);
  EXPECT_EQ(c.on_frame(heartbeat_frame(1, NmtState::PreOperational), 50'000),
            HeartbeatConsumer::Event::None);
  EXPECT_EQ(c.on_frame(heartbeat_frame(1, NmtState::Operational), 100'000),
            HeartbeatConsumer::Event::StateChanged);
  EXPECT_EQ(c.node(1)->state, NmtState::Operational);
  // Heartbeats of other nodes do not keep node 1 alive.
  c.on_frame(heartbeat_frame(2, NmtState::Operational), 200'000);
  EXPECT_FALSE(c.poll_lost(250'000).has_value());  // exactly at the timeout: still alive
  EXPECT_EQ(c.poll_lost(250'001), std::optional<uint8_t>(1));
  EXPECT_FALSE(c.node(1)->alive);
  EXPECT_FALSE(c.poll_lost(400'000).has_value());  // reported once
  EXPECT_EQ(c.on_frame(heartbeat_frame(1, NmtState::Operational), 500'000),
            HeartbeatConsumer::Event::StateChanged);  // back
}

TEST(CanopenVirtualBus, DeliversToEveryOtherEndpointOnly) {
  VirtualCanBus bus;
  auto& a = bus.attach();
  auto& b = bus.attach();
  auto& c = bus.attach();
  EXPECT_TRUE(a.send(heartbeat_frame(1, NmtState::Operational)));
  CanFrame f;
  EXPECT_FALSE(a.receive(f));
  ASSERT_TRUE(b.receive(f));
  EXPECT_EQ(f.id, 0x701u);
  ASSERT_TRUE(c.receive(f));
  c.set_connected(false);
  a.send(heartbeat_frame(1, NmtState::Operational));
  EXPECT_FALSE(c.receive(f));
  b.set_error_state(true, false);
  EXPECT_FALSE(b.send(heartbeat_frame(2, NmtState::Operational)));  // bus-off: nothing leaves
  EXPECT_EQ(b.status().tx_dropped, 1u);
  EXPECT_EQ(b.status().error_frames, 1u);
}

TEST(CanopenSocketCan, MissingInterfaceIsAnErrorNamingIt) {
  // Without AF_CAN the socket fails, with it the interface lookup: either way the message
  // names the interface and nothing is left open.
  try {
    SocketCanBus bus("rackcat-none0");
    FAIL() << "opened a CAN interface that does not exist";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("rackcat-none0"), std::string::npos) << e.what();
  }
  EXPECT_THROW(SocketCanBus("an-interface-name-too-long"), std::runtime_error);
}
