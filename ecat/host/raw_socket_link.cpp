#include "ecat/host/raw_socket_link.hpp"

#include <arpa/inet.h>
#include <linux/filter.h>
#include <linux/if_ether.h>
#include <linux/if_packet.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>
#include <cerrno>
#include <cstring>
#include <ctime>

namespace rackcat::ecat {
namespace {

// Older kernel headers lack it; the value is ABI (linux/if_packet.h, Linux 4.20).
#ifndef PACKET_IGNORE_OUTGOING
constexpr int PACKET_IGNORE_OUTGOING = 23;
#endif

constexpr size_t kEthHeader = 14;
constexpr size_t kVlanTag = 4;
constexpr uint16_t kEtherTypeVlan = 0x8100;
constexpr size_t kEthTypeOffset = 12;
// Control messages of one receive: the receive timestamp (SO_TIMESTAMPNS, which the kernel
// puts first) and the VLAN tag (PACKET_AUXDATA).
constexpr size_t kControlBytes = CMSG_SPACE(sizeof(timespec)) + CMSG_SPACE(sizeof(tpacket_auxdata));

// The control message of one level and type that a receive returned, with room for a T, copied
// out; false when the kernel gave none.
template <typename T>
bool control_message(msghdr& msg, int level, int type, T& out) {
  for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c)) {
    if (c->cmsg_level == level && c->cmsg_type == type && c->cmsg_len >= CMSG_LEN(sizeof(T))) {
      std::memcpy(&out, CMSG_DATA(c), sizeof(T));
      return true;
    }
  }
  return false;
}

// The kernel's receive timestamp of a packet (CLOCK_REALTIME ns), 0 when it gave none.
uint64_t receive_timestamp_ns(msghdr& msg) {
  timespec ts{};
  if (!control_message(msg, SOL_SOCKET, SCM_TIMESTAMPNS, ts)) return 0;
  return static_cast<uint64_t>(ts.tv_sec) * 1'000'000'000ull + static_cast<uint64_t>(ts.tv_nsec);
}

std::string errno_text(int err) {
  return std::strerror(err);
}

[[noreturn]] void fail_open(const std::string& iface, const char* step, int err) {
  if (err == EPERM || err == EACCES) {
    throw LinkError(
        LinkErrorKind::NoPermission,
        "cannot open raw socket on " + iface + ": permission denied (needs root or CAP_NET_RAW)");
  }
  if (err == ENODEV || err == ENXIO) {
    throw LinkError(LinkErrorKind::NoInterface, "no such network interface: " + iface);
  }
  throw LinkError(LinkErrorKind::System,
                  "cannot open raw socket on " + iface + ": " + step + ": " + errno_text(err));
}

// Kernel-side filter: keep frames whose EtherType is 0x88A4 and that were not sent by this
// host. Everything else is dropped before it is queued on the socket, so a busy interface
// with other traffic costs the receiver nothing.
void attach_filter(int fd) {
  // Jump offsets count from the next instruction: index 4 drops, index 5 keeps.
  static sock_filter code[] = {
      // A = packet type (SKF_AD_PKTTYPE); PACKET_OUTGOING (4) -> drop.
      BPF_STMT(BPF_LD | BPF_W | BPF_ABS, static_cast<uint32_t>(SKF_AD_OFF + SKF_AD_PKTTYPE)),
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, PACKET_OUTGOING, 2, 0),
      // A = EtherType (half-word at offset 12); 0x88A4 -> keep, else drop.
      BPF_STMT(BPF_LD | BPF_H | BPF_ABS, kEthTypeOffset),
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, RawSocketLink::kEtherTypeEcat, 1, 0),
      BPF_STMT(BPF_RET | BPF_K, 0),
      BPF_STMT(BPF_RET | BPF_K, 0xFFFF),
  };
  sock_fprog prog{static_cast<unsigned short>(sizeof(code) / sizeof(code[0])), code};
  // A failure only costs the software check in try_receive(); not fatal.
  (void)setsockopt(fd, SOL_SOCKET, SO_ATTACH_FILTER, &prog, sizeof(prog));
}

}  // namespace

RawSocketLink::RawSocketLink(const std::string& interface_name) : name_(interface_name) {
  if (name_.empty() || name_.size() >= IFNAMSIZ) {
    throw LinkError(LinkErrorKind::NoInterface, "no such network interface: '" + name_ + "'");
  }
  // A missing interface is reported as such even when we could not open the socket either.
  if (if_nametoindex(name_.c_str()) == 0) {
    throw LinkError(LinkErrorKind::NoInterface, "no such network interface: " + name_);
  }
  // Protocol 0: receive nothing until bind() names both the interface and the EtherType, so
  // no frame from another interface is ever queued.
  fd_ = ::socket(AF_PACKET, SOCK_RAW | SOCK_CLOEXEC, 0);
  if (fd_ < 0) fail_open(name_, "socket", errno);
  try {
    ifreq ifr{};
    std::memcpy(ifr.ifr_name, name_.c_str(), name_.size() + 1);
    if (::ioctl(fd_, SIOCGIFINDEX, &ifr) < 0) fail_open(name_, "SIOCGIFINDEX", errno);
    ifindex_ = ifr.ifr_ifindex;
    if (::ioctl(fd_, SIOCGIFHWADDR, &ifr) < 0) fail_open(name_, "SIOCGIFHWADDR", errno);
    std::memcpy(mac_.data(), ifr.ifr_hwaddr.sa_data, mac_.size());

    attach_filter(fd_);
    int one = 1;
    // Not available on every kernel; both only save work.
    (void)setsockopt(fd_, SOL_PACKET, PACKET_IGNORE_OUTGOING, &one, sizeof(one));
    (void)setsockopt(fd_, SOL_PACKET, PACKET_QDISC_BYPASS, &one, sizeof(one));
    // Receive timestamps, for try_receive_sent_before(); without them that finds no frame.
    (void)setsockopt(fd_, SOL_SOCKET, SO_TIMESTAMPNS, &one, sizeof(one));
    // The VLAN tag of a tagged frame, which the kernel strips before we see the frame.
    if (setsockopt(fd_, SOL_PACKET, PACKET_AUXDATA, &one, sizeof(one)) < 0) {
      fail_open(name_, "PACKET_AUXDATA", errno);
    }

    sockaddr_ll addr{};
    addr.sll_family = AF_PACKET;
    // ETH_P_ALL, not 0x88A4: the kernel clears a stripped VLAN tag before it hands a frame to
    // sockets bound to one EtherType, and keeps it (in PACKET_AUXDATA) only for taps on every
    // protocol. The filter above still keeps nothing but EtherCAT.
    addr.sll_protocol = htons(ETH_P_ALL);
    addr.sll_ifindex = ifindex_;
    if (::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) < 0) {
      fail_open(name_, "bind", errno);
    }

    packet_mreq mreq{};
    mreq.mr_ifindex = ifindex_;
    mreq.mr_type = PACKET_MR_PROMISC;
    if (setsockopt(fd_, SOL_PACKET, PACKET_ADD_MEMBERSHIP, &mreq, sizeof(mreq)) < 0) {
      fail_open(name_, "PACKET_ADD_MEMBERSHIP", errno);
    }
  } catch (...) {
    ::close(fd_);
    fd_ = -1;
    throw;
  }
}

RawSocketLink::~RawSocketLink() {
  if (fd_ >= 0) ::close(fd_);
}

std::span<uint8_t> RawSocketLink::try_receive() {
  return receive(kAnyTime);
}

std::span<uint8_t> RawSocketLink::try_receive_sent_before(uint64_t realtime_ns) {
  return receive(realtime_ns);
}

std::span<uint8_t> RawSocketLink::receive(uint64_t sent_before) {
  for (;;) {
    if (sent_before != kAnyTime && !next_arrived_before(sent_before)) return {};
    switch (receive_one()) {
      case Received::Frame:
        return {rx_.data(), rx_len_};
      case Received::Skipped:
        continue;
      case Received::Nothing:
        return {};
    }
  }
}

bool RawSocketLink::next_arrived_before(uint64_t realtime_ns) {
  // The next packet's receive timestamp, without taking the packet (no data copied); the
  // receive that follows takes exactly that packet: this thread is the socket's only reader.
  alignas(cmsghdr) uint8_t control[kControlBytes];
  msghdr msg{};
  msg.msg_control = control;
  msg.msg_controllen = sizeof(control);
  if (::recvmsg(fd_, &msg, MSG_DONTWAIT | MSG_PEEK | MSG_TRUNC) < 0) return false;
  const uint64_t arrived = receive_timestamp_ns(msg);
  return arrived != 0 && arrived < realtime_ns;
}

RawSocketLink::Received RawSocketLink::receive_one() {
  sockaddr_ll from{};
  // Room for a tag the kernel took off (below): the frame is received 4 bytes short of the
  // buffer.
  iovec iov{rx_.data(), rx_.size() - kVlanTag};
  alignas(cmsghdr) uint8_t control[kControlBytes];
  msghdr msg{};
  msg.msg_name = &from;
  msg.msg_namelen = sizeof(from);
  msg.msg_iov = &iov;
  msg.msg_iovlen = 1;
  msg.msg_control = control;
  msg.msg_controllen = sizeof(control);
  const ssize_t n = ::recvmsg(fd_, &msg, MSG_DONTWAIT | MSG_TRUNC);
  if (n < 0) {
    // EAGAIN: nothing pending. EINTR: a signal; the caller's loop looks at it.
    // Anything else (ENETDOWN while the interface goes down) also means "no frame now".
    return Received::Nothing;
  }
  size_t len = static_cast<size_t>(n);
  // Same checks as the kernel filter, for kernels where it could not be attached.
  if (from.sll_pkttype == PACKET_OUTGOING || len < kEthHeader || len > iov.iov_len ||
      rx_[kEthTypeOffset] != (kEtherTypeEcat >> 8) ||
      rx_[kEthTypeOffset + 1] != (kEtherTypeEcat & 0xFF)) {
    ++ignored_;
    return Received::Skipped;
  }
  // An IEEE 802.1Q tag the kernel (or the NIC) stripped comes back in PACKET_AUXDATA: put
  // it back where it was, so the frame is processed and answered as it arrived, tagged and
  // at full length (ETG.1000.4 §5.3, docs/ESC.md).
  tpacket_auxdata aux{};
  if (control_message(msg, SOL_PACKET, PACKET_AUXDATA, aux) &&
      (aux.tp_status & TP_STATUS_VLAN_VALID) != 0) {
    const uint16_t tpid =
        (aux.tp_status & TP_STATUS_VLAN_TPID_VALID) ? aux.tp_vlan_tpid : kEtherTypeVlan;
    std::memmove(&rx_[kEthTypeOffset + kVlanTag], &rx_[kEthTypeOffset], len - kEthTypeOffset);
    rx_[kEthTypeOffset] = static_cast<uint8_t>(tpid >> 8);
    rx_[kEthTypeOffset + 1] = static_cast<uint8_t>(tpid);
    rx_[kEthTypeOffset + 2] = static_cast<uint8_t>(aux.tp_vlan_tci >> 8);
    rx_[kEthTypeOffset + 3] = static_cast<uint8_t>(aux.tp_vlan_tci);
    len += kVlanTag;
    ++vlan_tagged_;
  }
  ++rx_frames_;
  rx_len_ = len;
  return Received::Frame;
}

bool RawSocketLink::send(std::span<const uint8_t> frame) {
  for (;;) {
    ssize_t n = ::send(fd_, frame.data(), frame.size(), 0);
    if (n == static_cast<ssize_t>(frame.size())) {
      ++tx_frames_;
      return true;
    }
    if (n < 0 && errno == EINTR) continue;
    ++tx_errors_;
    return false;
  }
}

}  // namespace rackcat::ecat
