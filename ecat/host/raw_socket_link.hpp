// The wire: a raw AF_PACKET socket bound to one network interface that carries EtherCAT
// frames (EtherType 0x88A4, ETG.1000.4 §5.1) and nothing else.
//
// Frames arrive in a receive ring shared with the kernel (PACKET_RX_RING, TPACKET_V2,
// packet_mmap.rst): the kernel copies each frame into the next free slot as it is delivered,
// so taking a frame is a load of the slot's status - no system call and no second copy on
// the path from the master's frame to the reply - and the frame is answered in place in its
// slot. Where the ring cannot be set up the link receives with recvmsg into one fixed
// buffer instead. Receiving and sending never allocate. Frames we send ourselves are not looped
// back to us (PACKET_IGNORE_OUTGOING, with a packet-type check as a fallback on kernels without
// it), and the interface is put in promiscuous mode for the socket's lifetime because a real ESC
// answers every EtherCAT frame whatever its destination MAC address.
#pragma once

#include <linux/if_packet.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>

#include "base/cache_line.hpp"

namespace rackcat::ecat {

// Why opening the link failed. The runner turns NoInterface and NoPermission into a
// one-line message and exit code 2 (a configuration problem, not a runtime failure).
enum class LinkErrorKind { NoInterface, NoPermission, System };

class LinkError : public std::runtime_error {
 public:
  LinkError(LinkErrorKind kind, const std::string& what) : std::runtime_error(what), kind_(kind) {}
  LinkErrorKind kind() const { return kind_; }

 private:
  LinkErrorKind kind_;
};

struct LinkOptions {
  // Receive through the shared ring (true) or with a recvmsg per frame (false; also what a
  // kernel that refuses the ring gets). Both give the same frames.
  bool receive_ring = true;
};

// How the receiver waits for the next frame: sleep in the kernel until one arrives, or spin
// on non-blocking receives (lower latency, one core busy).
enum class WaitMode { Blocking, BusyPoll };

class RawSocketLink {
 public:
  static constexpr uint16_t kEtherTypeEcat = 0x88A4;
  // Largest Ethernet frame without FCS (1514) with room for one VLAN tag; anything longer is
  // truncated by the kernel and dropped by receive().
  static constexpr size_t kMaxFrame = 1536;

  // Opens and binds the socket; throws LinkError. Needs CAP_NET_RAW only here: the open
  // socket keeps working after the process drops all its capabilities.
  explicit RawSocketLink(const std::string& interface_name, LinkOptions options = {});
  ~RawSocketLink();
  RawSocketLink(const RawSocketLink&) = delete;
  RawSocketLink& operator=(const RawSocketLink&) = delete;

  // Receives one EtherCAT frame into the link's buffer without waiting. Returns the frame
  // (Ethernet header included), or an empty span when no frame is pending. Non-EtherCAT and
  // truncated frames are consumed and skipped. A VLAN tag the kernel stripped is put back
  // (PACKET_AUXDATA), so the frame is exactly what was on the wire. The span stays valid until
  // release() or the next receive; the caller may change it in place (and send it).
  std::span<uint8_t> try_receive();
  // Gives the last received frame's slot back to the kernel. Call it once the frame is
  // answered, before sleeping on fd(): a slot still held makes the socket poll readable.
  void release() {
    if (held_ != nullptr) release_slot();
  }
  // Whether try_receive() may find a frame: with the ring, whether the next slot is ours (one
  // load, no system call); without it, always true (only a receive can tell).
  bool frame_pending() const {
    if (ring_ == nullptr) return true;
    const auto* hdr = reinterpret_cast<const tpacket2_hdr*>(ring_ + ring_head_ * kRingFrameSize);
    return (__atomic_load_n(&hdr->tp_status, __ATOMIC_ACQUIRE) & TP_STATUS_USER) != 0;
  }
  // Takes the socket's pending error (ENETDOWN when the interface went down), which keeps
  // poll() reporting POLLERR until it is taken. The recvmsg path takes it with every receive;
  // the ring path never enters the kernel to receive, so the waiting loop calls this.
  void clear_error();
  // Whether frames arrive through the shared ring (LinkOptions::receive_ring, if the kernel
  // took it).
  bool uses_receive_ring() const { return ring_ != nullptr; }

  // Sends a complete Ethernet frame (header included, without FCS). Returns false when the
  // kernel refused it (the error is counted, the caller carries on: a lost reply is what a
  // real line does with a damaged frame, and the master retries).
  bool send(std::span<const uint8_t> frame);

  int fd() const { return fd_; }
  int ifindex() const { return ifindex_; }
  const std::string& interface_name() const { return name_; }
  const std::array<uint8_t, 6>& mac() const { return mac_; }

  uint64_t frames_received() const { return rx_frames_; }
  uint64_t frames_sent() const { return tx_frames_; }
  uint64_t frames_ignored() const { return ignored_; }
  // Frames that arrived with an IEEE 802.1Q tag (recovered from PACKET_AUXDATA).
  uint64_t frames_vlan_tagged() const { return vlan_tagged_; }
  uint64_t send_errors() const { return tx_errors_; }

 private:
  std::string name_;
  // The receive ring: kRingFrames slots of kRingFrameSize bytes, each a tpacket2_hdr, the
  // sender's sockaddr_ll and the frame at the header's tp_mac.
  static constexpr size_t kRingFrameSize = 2048;
  static constexpr size_t kRingBlockSize = 4096;
  static constexpr size_t kRingFrames = 128;
  void setup_receive_ring();
  std::span<uint8_t> receive_from_ring();
  std::span<uint8_t> receive_with_recvmsg();
  void release_slot();
  // A frame whose VLAN tag the kernel stripped, with the tag put back, in rx_.
  std::span<uint8_t> with_vlan_tag(const uint8_t* frame, size_t len, uint16_t tpid, uint16_t tci);

  int fd_ = -1;
  int ifindex_ = 0;
  uint8_t* ring_ = nullptr;  // mmap'd, kRingFrames x kRingFrameSize
  size_t ring_head_ = 0;     // the next slot the kernel fills in order
  void* held_ = nullptr;     // the slot of the frame last returned, until release()
  std::array<uint8_t, 6> mac_{};
  alignas(base::kCacheLine) std::array<uint8_t, kMaxFrame> rx_{};
  uint64_t rx_frames_ = 0;
  uint64_t tx_frames_ = 0;
  uint64_t ignored_ = 0;
  uint64_t vlan_tagged_ = 0;
  uint64_t tx_errors_ = 0;
};

}  // namespace rackcat::ecat
