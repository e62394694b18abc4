// RawSocketLink: the errors a user sees when starting the slave, and that only EtherCAT
// frames reach the ESCs. Tests that need a raw socket run on the loopback interface and
// skip when the process lacks CAP_NET_RAW.
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <linux/if_packet.h>
#include <net/if.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>
#include <chrono>
#include <cstring>
#include <vector>

#include "ecat/host/privileges.hpp"
#include "ecat/host/raw_socket_link.hpp"
#include "tests/ecat/link_test_util.hpp"

namespace rackcat::ecat {
namespace {

TEST(LinkSocket, MissingInterfaceIsANoInterfaceError) {
  try {
    RawSocketLink link("rackcat-nope0");
    FAIL() << "expected LinkError";
  } catch (const LinkError& e) {
    EXPECT_EQ(e.kind(), LinkErrorKind::NoInterface);
    EXPECT_STREQ(e.what(), "no such network interface: rackcat-nope0");
  }
}

TEST(LinkSocket, OverlongInterfaceNameIsANoInterfaceError) {
  try {
    RawSocketLink link(std::string(40, 'x'));
    FAIL() << "expected LinkError";
  } catch (const LinkError& e) {
    EXPECT_EQ(e.kind(), LinkErrorKind::NoInterface);
  }
}

TEST(LinkSocket, WithoutCapNetRawOpeningIsANoPermissionError) {
  // In a child, so this process keeps its privileges for the other tests.
  const int status = testutil::in_child([] {
    drop_privileges({.user = "", .use_sudo_user = false});
    try {
      RawSocketLink link("lo");
    } catch (const LinkError& e) {
      if (e.kind() != LinkErrorKind::NoPermission) return 2;
      if (std::string(e.what()).find("permission denied") == std::string::npos) return 3;
      return 0;
    }
    return 1;
  });
  EXPECT_EQ(status, 0);
}

TEST(LinkSocket, OnlyEtherCatFramesAreReceived) {
  if (!testutil::can_open_raw_socket()) GTEST_SKIP() << "needs root or CAP_NET_RAW";
  RawSocketLink link("lo");
  testutil::RawSender sender("lo");
  // An IPv4-typed frame and an EtherCAT frame with a recognisable payload.
  auto other = testutil::ethercat_frame(0x11);
  other[12] = 0x08;
  other[13] = 0x00;
  sender.send(other);
  const auto ecat = testutil::ethercat_frame(0x22);
  sender.send(ecat);
  const auto got = testutil::receive_matching(link, [](std::span<const uint8_t> f) {
    return f.size() > testutil::kFirstDataByte &&
           (f[testutil::kFirstDataByte] == 0x11 || f[testutil::kFirstDataByte] == 0x22);
  });
  ASSERT_FALSE(got.empty());
  EXPECT_EQ(got, ecat);
}

TEST(LinkSocket, SendsWholeFramesThatArriveUnchanged) {
  if (!testutil::can_open_raw_socket()) GTEST_SKIP() << "needs root or CAP_NET_RAW";
  RawSocketLink sender_link("lo");
  RawSocketLink receiver("lo");
  const auto frame = testutil::ethercat_frame(0x33);
  ASSERT_TRUE(sender_link.send(frame));
  EXPECT_EQ(sender_link.frames_sent(), 1u);
  const auto got = testutil::receive_matching(receiver, [](std::span<const uint8_t> f) {
    return f.size() > testutil::kFirstDataByte && f[testutil::kFirstDataByte] == 0x33;
  });
  EXPECT_EQ(got, frame);
}

}  // namespace
}  // namespace rackcat::ecat
