// The wire: a raw AF_PACKET socket bound to one network interface that carries EtherCAT
// frames (EtherType 0x88A4, ETG.1000.4 §5.1) and nothing else.
//
// The link owns one fixed receive buffer; receiving and sending never allocate. Frames we
// send ourselves are not looped back to us (PACKET_IGNORE_OUTGOING, with a packet-type check
// as a fallback on kernels without it), and the interface is put in promiscuous mode for the
// socket's lifetime because a real ESC answers every EtherCAT frame whatever its destination
// MAC address.
#pragma once

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
  explicit RawSocketLink(const std::string& interface_name);
  ~RawSocketLink();
  RawSocketLink(const RawSocketLink&) = delete;
  RawSocketLink& operator=(const RawSocketLink&) = delete;

  // Receives one EtherCAT frame into the link's buffer without waiting. Returns the frame
  // (Ethernet header included), or an empty span when no frame is pending. Non-EtherCAT and
  // truncated frames are consumed and skipped. A VLAN tag the kernel stripped is put back
  // (PACKET_AUXDATA), so the frame is exactly what was on the wire. The span stays valid until
  // the next receive.
  std::span<uint8_t> try_receive();

  // Like try_receive(), but only a frame that reached this socket before `realtime_ns`
  // (CLOCK_REALTIME nanoseconds, against the kernel's receive timestamp, SO_TIMESTAMPNS): the
  // event loop's test for "sent by a master that had not yet seen our last reply". Empty when
  // nothing is pending, when the next frame came at or after `realtime_ns` (it stays queued for
  // try_receive()) or when the kernel gives no timestamp.
  std::span<uint8_t> try_receive_sent_before(uint64_t realtime_ns);

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
  static constexpr uint64_t kAnyTime = UINT64_MAX;
  // The next EtherCAT frame, skipping other packets; with sent_before, only while the next
  // packet arrived before that time (next_arrived_before).
  std::span<uint8_t> receive(uint64_t sent_before);
  bool next_arrived_before(uint64_t realtime_ns);
  enum class Received { Frame, Skipped, Nothing };
  // One recvmsg: a frame into rx_ (its length in rx_len_), a packet that is not one, or none.
  Received receive_one();

  std::string name_;
  int fd_ = -1;
  int ifindex_ = 0;
  std::array<uint8_t, 6> mac_{};
  alignas(base::kCacheLine) std::array<uint8_t, kMaxFrame> rx_{};
  size_t rx_len_ = 0;
  uint64_t rx_frames_ = 0;
  uint64_t tx_frames_ = 0;
  uint64_t ignored_ = 0;
  uint64_t vlan_tagged_ = 0;
  uint64_t tx_errors_ = 0;
};

}  // namespace rackcat::ecat
