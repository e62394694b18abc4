// RawSocketLink: the errors a user sees when starting the slave, that only EtherCAT frames
// reach the ESCs, that they arrive as they were on the wire (a VLAN tag the kernel stripped
// put back, in order) and that a link whose interface went down and came back works again. Tests
// that need a raw socket run on the loopback interface (those that need it quiet on one of their
// own, in a network namespace of a child process) and skip when the process lacks CAP_NET_RAW.
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <linux/if_packet.h>
#include <net/if.h>
#include <poll.h>
#include <sched.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>
#include <chrono>
#include <cstring>
#include <functional>
#include <thread>
#include <vector>

#include "ecat/host/event_loop.hpp"
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

// Events poll() reports on the link's socket right now.
short poll_now(const RawSocketLink& link) {
  pollfd pfd{link.fd(), POLLIN, 0};
  return poll(&pfd, 1, 0) > 0 ? pfd.revents : 0;
}

TEST(LinkReceive, VlanTaggedFrameArrivesWithItsTagAtFullLength) {
  testutil::expect_ok_in_own_network([] {
    RawSocketLink link("lo");
    testutil::RawSender sender("lo");
    // The tag (TPID 0x8100, priority 5, VLAN 42) after the addresses, as on the wire; the
    // kernel strips it before the socket sees the frame.
    auto plain = testutil::ethercat_frame(0x55);
    std::vector<uint8_t> tagged(plain.begin(), plain.begin() + 12);
    for (const uint8_t b : {0x81, 0x00, 0xA0, 0x2A}) tagged.push_back(b);
    tagged.insert(tagged.end(), plain.begin() + 12, plain.end());
    if (!sender.send(tagged)) return 1;
    const auto got = testutil::receive_matching(link, [](std::span<const uint8_t> f) {
      return f.size() > testutil::kFirstDataByte + 4 && f[testutil::kFirstDataByte + 4] == 0x55;
    });
    if (got != tagged) return 2;
    if (link.frames_vlan_tagged() != 1) return 3;
    return 0;
  });
}

TEST(LinkReceive, FramesArriveInOrderAndNoneIsLost) {
  // 400 frames in bursts of 40 (a master with frames in flight): none lost or reordered.
  testutil::expect_ok_in_own_network([] {
    RawSocketLink link("lo");
    testutil::RawSender sender("lo");
    int expected = 0;
    for (int burst = 0; burst < 10; ++burst) {
      for (int i = 0; i < 40; ++i) {
        auto f = testutil::ethercat_frame(static_cast<uint8_t>(burst * 40 + i));
        f[testutil::kFirstDataByte + 1] = static_cast<uint8_t>((burst * 40 + i) >> 8);
        if (!sender.send(f)) return 1;
      }
      for (int i = 0; i < 40; ++i) {
        const auto f =
            testutil::receive_matching(link, [](std::span<const uint8_t>) { return true; });
        if (f.size() != 60) return 2;
        const int n = f[testutil::kFirstDataByte] | (f[testutil::kFirstDataByte + 1] << 8);
        if (n != expected++) return 3;
      }
    }
    if (link.frames_received() != 400) return 4;
    return 0;
  });
}

TEST(LinkReceive, ATakenFrameLeavesTheSocketQuiet) {
  // The waiting loop sleeps in poll() once the pending frames are taken: a frame still counted
  // as pending would wake it at once, forever.
  testutil::expect_ok_in_own_network([] {
    RawSocketLink link("lo");
    testutil::RawSender sender("lo");
    if (!sender.send(testutil::ethercat_frame(0x66))) return 1;
    pollfd pfd{link.fd(), POLLIN, 0};
    if (poll(&pfd, 1, 2000) != 1 || (pfd.revents & POLLIN) == 0) return 2;
    const auto f = link.try_receive();
    if (f.empty() || f[testutil::kFirstDataByte] != 0x66) return 3;
    if (poll_now(link) != 0) return 4;
    if (!link.try_receive().empty()) return 5;
    return 0;
  });
}

// The event loop's burst test (event_loop.hpp): a frame that arrived before the bound is taken,
// one that arrived after it stays queued for try_receive(), in order.
TEST(LinkReceive, SentBeforeTakesOnlyFramesThatArrivedBeforeTheBound) {
  testutil::expect_ok_in_own_network([] {
    RawSocketLink link("lo");
    testutil::RawSender sender("lo");
    if (!testutil::wait_for_receive_timestamps(
            link, [&sender](const std::vector<uint8_t>& f) { return sender.send(f); })) {
      return 9;
    }
    const uint64_t probes = link.frames_received();
    if (!link.try_receive_sent_before(realtime_ns()).empty()) return 1;  // nothing pending
    if (!sender.send(testutil::ethercat_frame(0x71))) return 2;
    pollfd pfd{link.fd(), POLLIN, 0};
    if (poll(&pfd, 1, 2000) != 1) return 3;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    const uint64_t bound = realtime_ns();
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    if (!sender.send(testutil::ethercat_frame(0x72))) return 4;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    const auto first = link.try_receive_sent_before(bound);
    if (first.empty() || first[testutil::kFirstDataByte] != 0x71) return 5;
    if (!link.try_receive_sent_before(bound).empty()) return 6;  // 0x72 came after the bound
    const auto second = link.try_receive();
    if (second.empty() || second[testutil::kFirstDataByte] != 0x72) return 7;
    if (link.frames_received() != probes + 2) return 8;
    return 0;
  });
}

TEST(LinkReceive, InterfaceDownIsReportedOnceAndFramesFlowWhenItIsBack) {
  testutil::expect_ok_in_own_network([] {
    RawSocketLink link("lo");
    if (!testutil::set_up("lo", false)) return 1;
    // ENETDOWN is pending: poll says so until a receive takes the error (the waiting loop
    // receives on POLLERR, so it does not spin on it), and then sleeps again.
    if ((poll_now(link) & POLLERR) == 0) return 2;
    if (!link.try_receive().empty()) return 3;
    if (poll_now(link) != 0) return 4;
    if (!testutil::set_up("lo", true)) return 5;
    testutil::RawSender sender("lo");
    if (!sender.send(testutil::ethercat_frame(0x77))) return 6;
    const auto got = testutil::receive_matching(link, [](std::span<const uint8_t> f) {
      return f.size() > testutil::kFirstDataByte && f[testutil::kFirstDataByte] == 0x77;
    });
    return got.empty() ? 7 : 0;
  });
}

}  // namespace
}  // namespace rackcat::ecat
