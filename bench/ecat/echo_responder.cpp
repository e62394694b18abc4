// The floor for the wire benchmark (scripts/wire_bench.py): the least work a responder on a
// raw AF_PACKET socket can do to answer an EtherCAT frame. It bumps the working counter of
// every datagram by one, sets bit 0x02 of the first source-MAC byte as an ESC does
// (ETG.1000.4 §5.1) and sends the frame back. No ESC model, no pcap, no timers.
//
//   echo_responder --iface IFACE [--busy-poll]
//
// Blocking mode sleeps in recv(); busy-poll spins on recv(MSG_DONTWAIT). Runs until SIGINT
// or SIGTERM. Exit code 2 when the interface is missing or the socket cannot be opened.
#include <arpa/inet.h>
#include <linux/if_ether.h>
#include <linux/if_packet.h>
#include <net/if.h>
#include <sys/socket.h>
#include <unistd.h>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>

namespace {

constexpr uint16_t kEtherTypeEcat = 0x88A4;
constexpr size_t kEthHeader = 14;
constexpr size_t kEcatHeader = 2;
constexpr size_t kDatagramHeader = 10;
constexpr size_t kWkcSize = 2;

std::atomic<bool> g_stop{false};

void on_signal(int) {
  g_stop.store(true);
}

// Adds one to each datagram's working counter (ETG.1000.4 §5.2.2: header, data, WKC; the
// "more datagrams follow" flag is bit 15 of the length word).
void bump_working_counters(uint8_t* frame, size_t len) {
  size_t pos = kEthHeader + kEcatHeader;
  while (pos + kDatagramHeader + kWkcSize <= len) {
    const uint16_t len_word = static_cast<uint16_t>(frame[pos + 6] | (frame[pos + 7] << 8));
    const size_t data_len = len_word & 0x07FF;
    const size_t wkc_pos = pos + kDatagramHeader + data_len;
    if (wkc_pos + kWkcSize > len) return;
    const uint16_t wkc = static_cast<uint16_t>(frame[wkc_pos] | (frame[wkc_pos + 1] << 8)) + 1;
    frame[wkc_pos] = static_cast<uint8_t>(wkc);
    frame[wkc_pos + 1] = static_cast<uint8_t>(wkc >> 8);
    if ((len_word & 0x8000) == 0) return;
    pos = wkc_pos + kWkcSize;
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::string iface;
  bool busy = false;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--iface" && i + 1 < argc) {
      iface = argv[++i];
    } else if (arg == "--busy-poll") {
      busy = true;
    } else {
      std::fprintf(stderr, "usage: %s --iface IFACE [--busy-poll]\n", argv[0]);
      return 2;
    }
  }
  if (iface.empty()) {
    std::fprintf(stderr, "usage: %s --iface IFACE [--busy-poll]\n", argv[0]);
    return 2;
  }
  const unsigned ifindex = if_nametoindex(iface.c_str());
  if (ifindex == 0) {
    std::fprintf(stderr, "echo_responder: no such network interface: %s\n", iface.c_str());
    return 2;
  }
  const int fd = socket(AF_PACKET, SOCK_RAW, 0);
  if (fd < 0) {
    std::fprintf(stderr, "echo_responder: cannot open raw socket: %s\n", std::strerror(errno));
    return 2;
  }
  int one = 1;
  (void)setsockopt(fd, SOL_PACKET, PACKET_IGNORE_OUTGOING, &one, sizeof(one));
  (void)setsockopt(fd, SOL_PACKET, PACKET_QDISC_BYPASS, &one, sizeof(one));
  sockaddr_ll addr{};
  addr.sll_family = AF_PACKET;
  addr.sll_protocol = htons(kEtherTypeEcat);
  addr.sll_ifindex = static_cast<int>(ifindex);
  if (bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) < 0) {
    std::fprintf(stderr, "echo_responder: bind %s: %s\n", iface.c_str(), std::strerror(errno));
    return 2;
  }
  // No SA_RESTART: a blocking recv() returns EINTR and the loop sees the flag.
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);

  alignas(64) static uint8_t buf[2048];
  const int flags = busy ? MSG_DONTWAIT : 0;
  while (!g_stop.load(std::memory_order_relaxed)) {
    sockaddr_ll from{};
    socklen_t from_len = sizeof(from);
    const ssize_t n =
        recvfrom(fd, buf, sizeof(buf), flags, reinterpret_cast<sockaddr*>(&from), &from_len);
    if (n < static_cast<ssize_t>(kEthHeader + kEcatHeader)) continue;
    if (from.sll_pkttype == PACKET_OUTGOING) continue;
    bump_working_counters(buf, static_cast<size_t>(n));
    buf[6] |= 0x02;
    (void)send(fd, buf, static_cast<size_t>(n), 0);
  }
  close(fd);
  return 0;
}
