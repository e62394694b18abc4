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

namespace rackcat::ecat {
namespace {

// Older kernel headers lack it; the value is ABI (linux/if_packet.h, Linux 4.20).
#ifndef PACKET_IGNORE_OUTGOING
constexpr int PACKET_IGNORE_OUTGOING = 23;
#endif

constexpr size_t kEthHeader = 14;
constexpr size_t kEthTypeOffset = 12;

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

    sockaddr_ll addr{};
    addr.sll_family = AF_PACKET;
    addr.sll_protocol = htons(kEtherTypeEcat);
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
  for (;;) {
    sockaddr_ll from{};
    socklen_t from_len = sizeof(from);
    ssize_t n = ::recvfrom(fd_, rx_.data(), rx_.size(), MSG_DONTWAIT | MSG_TRUNC,
                           reinterpret_cast<sockaddr*>(&from), &from_len);
    if (n < 0) {
      // EAGAIN: nothing pending. EINTR: a signal; the caller's loop looks at it.
      // Anything else (ENETDOWN while the interface goes down) also means "no frame now".
      return {};
    }
    const auto len = static_cast<size_t>(n);
    // Same checks as the kernel filter, for kernels where it could not be attached.
    if (from.sll_pkttype == PACKET_OUTGOING || len < kEthHeader || len > rx_.size() ||
        rx_[kEthTypeOffset] != (kEtherTypeEcat >> 8) ||
        rx_[kEthTypeOffset + 1] != (kEtherTypeEcat & 0xFF)) {
      ++ignored_;
      continue;
    }
    ++rx_frames_;
    return {rx_.data(), len};
  }
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
