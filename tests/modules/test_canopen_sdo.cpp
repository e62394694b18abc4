// SDO over CAN (CiA 301 §7.2.4.3) served by coe::SdoServer through CanSdoServer: expedited
// and segmented uploads, expedited download, aborts; and the control module's SdoClient.
// Expected bytes are written from CiA 301's command layouts.
#include <gtest/gtest.h>

#include "coe/bits.hpp"
#include "mdp/rack_config.hpp"
#include "modules/canopen/sdo_client.hpp"
#include "modules/canopen/virtual_bus.hpp"
#include "modules/rim/node.hpp"

using namespace rackcat;
using namespace rackcat::modules::canopen;

namespace {

class CanSdo : public ::testing::Test {
 protected:
  CanSdo()
      : rack(mdp::default_rack()),
        client_ep(bus.attach()),
        node_ep(bus.attach()),
        node(rack, 2, node_ep) {
    node.start(0);
    CanFrame f;
    while (client_ep.receive(f)) {
    }
  }
  // One request, one response (or none).
  std::optional<CanFrame> exchange(std::array<uint8_t, 8> request) {
    client_ep.send(CanFrame::make(0x602, request));
    node.step(now += 1000);
    CanFrame f;
    while (client_ep.receive(f)) {
      if (f.id == 0x582) return f;
    }
    return std::nullopt;
  }

  mdp::RackConfig rack;
  VirtualCanBus bus;
  VirtualCanBus::Endpoint& client_ep;
  VirtualCanBus::Endpoint& node_ep;
  RimNode node;
  Micros now = 0;
};

}  // namespace

TEST_F(CanSdo, ExpeditedUploadOfVendorId) {
  // Initiate upload 0x1018:01 -> 43 18 10 01 + 4 bytes (expedited, size indicated, n = 4).
  auto r = exchange({0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0});
  ASSERT_TRUE(r);
  EXPECT_EQ(r->len, 8);
  EXPECT_EQ(r->data[0], 0x43);
  EXPECT_EQ(r->data[1], 0x18);
  EXPECT_EQ(r->data[2], 0x10);
  EXPECT_EQ(r->data[3], 0x01);
  EXPECT_EQ(le::get32(&r->data[4]), rack.control.vendor_id);
  // 0x1001 error register, one byte: 4F (n = 1).
  r = exchange({0x40, 0x01, 0x10, 0x00, 0, 0, 0, 0});
  ASSERT_TRUE(r);
  EXPECT_EQ(r->data[0], 0x4F);
}

TEST_F(CanSdo, SegmentedUploadOfDeviceName) {
  const std::string name = rack.rim(2)->part_number;  // "FI-RM1200-00", 12 bytes
  ASSERT_GT(name.size(), 7u);
  // Initiate: 41 08 10 00 + size (segmented, size indicated), no data.
  auto r = exchange({0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0});
  ASSERT_TRUE(r);
  EXPECT_EQ(r->data[0], 0x41);
  EXPECT_EQ(le::get32(&r->data[4]), name.size());
  // Segment 1 (toggle 0): 00 + 7 bytes, more to come.
  r = exchange({0x60, 0, 0, 0, 0, 0, 0, 0});
  ASSERT_TRUE(r);
  EXPECT_EQ(r->data[0], 0x00);
  std::string got(r->data.begin() + 1, r->data.end());
  // Segment 2 (toggle 1): 0x10 | (7 - n) << 1 | last.
  r = exchange({0x70, 0, 0, 0, 0, 0, 0, 0});
  ASSERT_TRUE(r);
  const size_t n = name.size() - 7;
  EXPECT_EQ(r->data[0], 0x10 | ((7 - n) << 1) | 0x01);
  got.append(r->data.begin() + 1, r->data.begin() + 1 + static_cast<ptrdiff_t>(n));
  EXPECT_EQ(got, name);
}

TEST_F(CanSdo, WrongToggleAndUnknownObjectAbort) {
  auto r = exchange({0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0});
  ASSERT_TRUE(r);
  r = exchange({0x70, 0, 0, 0, 0, 0, 0, 0});  // toggle 1 first: wrong
  ASSERT_TRUE(r);
  EXPECT_EQ(r->data[0], 0x80);
  EXPECT_EQ(le::get32(&r->data[4]), 0x05030000u);  // toggle bit not alternated
  r = exchange({0x40, 0x34, 0x12, 0x00, 0, 0, 0, 0});
  ASSERT_TRUE(r);
  EXPECT_EQ(r->data[0], 0x80);
  EXPECT_EQ(r->data[1], 0x34);
  EXPECT_EQ(r->data[2], 0x12);
  EXPECT_EQ(le::get32(&r->data[4]), 0x06020000u);  // object does not exist
  // A client abort gets no answer.
  EXPECT_FALSE(exchange({0x80, 0x08, 0x10, 0x00, 0, 0, 0x04, 0x05}));
}

TEST_F(CanSdo, ExpeditedDownloadSetsHeartbeatTimeAndReadOnlyAborts) {
  // 2B 17 10 00 E8 03: write 1000 ms to 0x1017 (n = 2) -> 60 17 10 00.
  auto r = exchange({0x2B, 0x17, 0x10, 0x00, 0xE8, 0x03, 0, 0});
  ASSERT_TRUE(r);
  EXPECT_EQ(r->data[0], 0x60);
  EXPECT_EQ(node.dictionary().find(0x1017)->get_u(0), 1000u);
  r = exchange({0x23, 0x18, 0x10, 0x01, 1, 2, 3, 4});
  ASSERT_TRUE(r);
  EXPECT_EQ(r->data[0], 0x80);
  EXPECT_EQ(le::get32(&r->data[4]), 0x06010002u);  // read-only object
}

TEST_F(CanSdo, NoSdoInStopped) {
  client_ep.send(nmt_frame(NmtCommand::Stop, 2));
  node.step(now += 1000);
  EXPECT_FALSE(exchange({0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0}));
}

TEST_F(CanSdo, ClientReadsCardListSegmentedAndIdentityExpedited) {
  SdoClient client(2, 100'000);
  auto run = [&](uint16_t index, uint8_t sub) {
    client_ep.send(client.start_upload(index, sub, now));
    for (int i = 0; i < 100 && client.status() == SdoClient::Status::Busy; ++i) {
      node.step(now += 1000);
      CanFrame f, next;
      bool has_next = false;
      while (client_ep.receive(f)) {
        if (client.on_frame(f, now, next, has_next) && has_next) client_ep.send(next);
      }
    }
  };
  run(0x2001, 0);
  ASSERT_EQ(client.status(), SdoClient::Status::Done);
  EXPECT_EQ(client.data(), node.profile().card_list);
  ASSERT_EQ(client.data().size(), 4 * rack.rim(2)->slots.size());
  // First entry: slot 1, its card ID (guide Table 3).
  EXPECT_EQ(le::get16(&client.data()[0]), 1);
  EXPECT_EQ(le::get16(&client.data()[2]), rack.rim(2)->slots[0].card->card_id);
  run(0x1018, 2);
  ASSERT_EQ(client.status(), SdoClient::Status::Done);
  EXPECT_EQ(le::get32(client.data().data()), node.profile().identity.product_code);
  run(0x1018, 9);
  EXPECT_EQ(client.status(), SdoClient::Status::Aborted);
  EXPECT_EQ(client.abort_code(), coe::AbortCode::SubindexNotFound);
}

TEST_F(CanSdo, ClientTimesOutWhenNobodyAnswers) {
  SdoClient client(7, 100'000);  // no node 7
  client_ep.send(client.start_upload(0x1018, 1, 0));
  CanFrame abort;
  EXPECT_FALSE(client.poll(99'999, abort));
  ASSERT_TRUE(client.poll(100'000, abort));
  EXPECT_EQ(client.status(), SdoClient::Status::TimedOut);
  EXPECT_EQ(abort.id, 0x607u);
  EXPECT_EQ(abort.data[0], 0x80);
  EXPECT_EQ(le::get32(&abort.data[4]), 0x05040000u);
}
