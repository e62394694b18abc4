// Helpers for the link tests: a child process for tests that change process-wide state
// (capabilities, uid), raw frames on the loopback interface, and bounded waits.
#pragma once

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
#include <cstdint>
#include <cstring>
#include <functional>
#include <span>
#include <thread>
#include <vector>

#include "ecat/host/event_loop.hpp"
#include "ecat/host/raw_socket_link.hpp"

namespace rackcat::ecat::testutil {

// Runs fn in a forked child and returns its exit status (fn's return value), or -1 when the
// child died otherwise (signal, exception).
inline int in_child(const std::function<int()>& fn) {
  const pid_t pid = fork();
  if (pid == 0) {
    int rc = 100;
    try {
      rc = fn();
    } catch (...) {
      rc = 101;
    }
    _exit(rc);
  }
  int status = 0;
  if (waitpid(pid, &status, 0) != pid) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

inline bool can_open_raw_socket() {
  const int fd = socket(AF_PACKET, SOCK_RAW, 0);
  if (fd < 0) return false;
  close(fd);
  return true;
}

// Offset of the first data byte of the first datagram: Ethernet 14 + EtherCAT header 2 +
// datagram header 10.
inline constexpr size_t kFirstDataByte = 26;

// A 60-byte EtherCAT frame with one NOP datagram of 4 data bytes, the first of which is tag.
inline std::vector<uint8_t> ethercat_frame(uint8_t tag) {
  std::vector<uint8_t> f(60, 0);
  std::memset(f.data(), 0xFF, 6);                               // destination: broadcast
  const uint8_t src[6] = {0x00, 0x00, 0x5E, 0x00, 0x53, 0x01};  // documentation MAC
  std::memcpy(f.data() + 6, src, 6);
  f[12] = 0x88;
  f[13] = 0xA4;
  f[14] = 10 + 4 + 2;  // EtherCAT header: length 16, type 1
  f[15] = 0x10;
  f[16] = 0x00;  // NOP
  f[17] = 0x01;  // index
  f[22] = 4;     // data length
  f[kFirstDataByte] = tag;
  return f;
}

// A plain raw socket on an interface, for sending test frames from "the master".
class RawSender {
 public:
  explicit RawSender(const char* iface) {
    fd_ = socket(AF_PACKET, SOCK_RAW, 0);
    sockaddr_ll addr{};
    addr.sll_family = AF_PACKET;
    addr.sll_protocol = 0;  // send only
    addr.sll_ifindex = static_cast<int>(if_nametoindex(iface));
    bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof(addr));
  }
  ~RawSender() { close(fd_); }
  bool send(const std::vector<uint8_t>& f) {
    return ::send(fd_, f.data(), f.size(), 0) == static_cast<ssize_t>(f.size());
  }

 private:
  int fd_ = -1;
};

// The kernel turns receive timestamps on for the whole system a moment after the first socket
// asks for them (a deferred static key, net_enable_timestamp): a frame queued before that is
// stamped only when it is read. Tests of RawSocketLink::try_receive_sent_before wait until a
// probe frame (`send` puts it on the wire) comes with the time it arrived: taken as sent
// before a bound read after it had arrived. False after 2 s. rackcat opens its link long
// before a master's first frame.
inline bool wait_for_receive_timestamps(RawSocketLink& link,
                                        const std::function<bool(std::vector<uint8_t>)>& send) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(2);
  while (std::chrono::steady_clock::now() < until) {
    if (!send(ethercat_frame(0xEE))) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
    const bool stamped = !link.try_receive_sent_before(realtime_ns()).empty();
    while (!link.try_receive().empty()) {
    }
    if (stamped) return true;
  }
  return false;
}

// Brings interface `name` up or down (SIOCSIFFLAGS); false when the kernel refused.
inline bool set_up(const char* name, bool up) {
  const int fd = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return false;
  ifreq ifr{};
  std::strncpy(ifr.ifr_name, name, IFNAMSIZ - 1);
  bool ok = ioctl(fd, SIOCGIFFLAGS, &ifr) == 0;
  if (ok) {
    ifr.ifr_flags = static_cast<short>(up ? (ifr.ifr_flags | IFF_UP) : (ifr.ifr_flags & ~IFF_UP));
    ok = ioctl(fd, SIOCSIFFLAGS, &ifr) == 0;
  }
  close(fd);
  return ok;
}

// Runs fn in a child process with a network namespace of its own, its loopback interface up
// and quiet: no other test's frames. Returns fn's result; 90 when the namespace could not be
// made (the test is then skipped).
inline int in_own_network(const std::function<int()>& fn) {
  return in_child([&fn] {
    if (unshare(CLONE_NEWNET) != 0 || !set_up("lo", true)) return 90;
    return fn();
  });
}

// Runs a test body in a network namespace of its own (in_own_network) and reports its result;
// skips where the process cannot open a raw socket or make the namespace.
inline void expect_ok_in_own_network(const std::function<int()>& body) {
  if (!testutil::can_open_raw_socket()) GTEST_SKIP() << "needs root or CAP_NET_RAW";
  const int status = in_own_network(body);
  if (status == 90) GTEST_SKIP() << "cannot make a network namespace";
  EXPECT_EQ(status, 0);
}

// Receives from the link until a frame satisfies pred, or 2 s pass (then returns empty).
inline std::vector<uint8_t> receive_matching(
    RawSocketLink& link, const std::function<bool(std::span<const uint8_t>)>& pred) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(2);
  while (std::chrono::steady_clock::now() < until) {
    pollfd pfd{link.fd(), POLLIN, 0};
    poll(&pfd, 1, 50);
    for (auto f = link.try_receive(); !f.empty(); f = link.try_receive()) {
      if (pred(f)) return {f.begin(), f.end()};
    }
  }
  return {};
}

}  // namespace rackcat::ecat::testutil
