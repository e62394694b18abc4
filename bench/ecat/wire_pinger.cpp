// The master side of the wire benchmark (scripts/wire_bench.py): sends EtherCAT frames from
// a raw socket, one at a time, and measures each round trip until the reply (the same frame
// with bit 0x02 of the first source-MAC byte set, ETG.1000.4 §5.1) comes back.
//
//   wire_pinger --iface IFACE[,IFACE...] --frame brd|lrw [--count N] [--slaves N] [--lrw-bytes B]
//               [--busy-poll] [--setup-fmmu] [--warmup N] [--samples-out FILE]
//               [--frame-file FILE[+FILE...][,FILE...]] [--period-us P]
//
// --period-us paces the frames as a master's cycle does (ETG.1000.4 §5: the master sends its
// cyclic frame once per cycle): round i starts at start + i x P (absolute, clock_nanosleep; a
// busy-poll pinger spins to the deadline instead), and a round that starts late does not try to
// catch up. 0 (the default) sends back to back: each frame as soon as the previous reply came.
// With several interfaces, one round sends to each of them in turn.
//
// --frame-file replays a captured frame (raw Ethernet bytes, e.g. a master's cyclic LRW frame
// captured by scripts/op_bench.py) instead of --frame: the source MAC becomes the socket's,
// the first datagram's index (ETG.1000.4 §5.2) counts frames, and the reported working counter
// is the first datagram's. Several files, one per interface in the same order, give each
// responder the frame its own master configured (op_bench.py --kickcat: another slave stack's
// process image is laid out differently). FILE+FILE+... is one cycle of several frames (a
// process image larger than one frame, e.g. ethercrab's LRW datagrams of 1,024 slaves): they
// are sent one after the other with consecutive datagram indexes, the round trip ends with the
// last reply, and the working counter reported is the sum of the frames'.
//
// --setup-fmmu first maps B bytes of logical space per slave onto each slave's process RAM
// (FMMU0, read/write, APWR by position) so that LRW exercises the FMMU path of a real slave.
// Several interfaces are pinged in turn, frame by frame. Prints one line of JSON per interface:
// {"frame":..,"count":..,"lost":..,"p50_us":..,"p90_us":..,
// "p99_us":..,"min_us":..,"max_us":..,"wkc":..}; --samples-out also writes every round trip
// (ns, one per line) so several runs can be pooled. Exit code 2 on setup errors.
#include <arpa/inet.h>
#include <linux/if_ether.h>
#include <linux/if_packet.h>
#include <net/if.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>
#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace {

constexpr uint16_t kEtherTypeEcat = 0x88A4;
constexpr uint8_t kCmdApwr = 0x02;
constexpr uint8_t kCmdBrd = 0x07;
constexpr uint8_t kCmdLrw = 0x0C;
constexpr int kTimeoutNs = 10'000'000;
constexpr size_t kMaxFramesPerCycle = 16;

uint64_t now_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<uint64_t>(ts.tv_sec) * 1'000'000'000ull + static_cast<uint64_t>(ts.tv_nsec);
}

void put16(uint8_t* p, uint16_t v) {
  p[0] = static_cast<uint8_t>(v);
  p[1] = static_cast<uint8_t>(v >> 8);
}
void put32(uint8_t* p, uint32_t v) {
  put16(p, static_cast<uint16_t>(v));
  put16(p + 2, static_cast<uint16_t>(v >> 16));
}
uint16_t get16(const uint8_t* p) {
  return static_cast<uint16_t>(p[0] | (p[1] << 8));
}

struct Frame {
  std::vector<uint8_t> bytes;
  size_t wkc_offset = 0;
};

// Ethernet + EtherCAT header + one datagram (ETG.1000.4 §5.2) + padding to the 60-byte
// Ethernet minimum.
Frame build_frame(const uint8_t* src_mac, uint8_t cmd, uint16_t adp, uint16_t ado,
                  const std::vector<uint8_t>& data) {
  Frame f;
  const size_t dgram = 10 + data.size() + 2;
  f.bytes.assign(std::max<size_t>(14 + 2 + dgram, 60), 0);
  uint8_t* p = f.bytes.data();
  std::memset(p, 0xFF, 6);
  std::memcpy(p + 6, src_mac, 6);
  p[12] = kEtherTypeEcat >> 8;
  p[13] = kEtherTypeEcat & 0xFF;
  put16(p + 14, static_cast<uint16_t>(dgram | (1u << 12)));  // length, type 1 (datagrams)
  uint8_t* d = p + 16;
  d[0] = cmd;
  d[1] = 0;  // index, set per frame
  put16(d + 2, adp);
  put16(d + 4, ado);
  put16(d + 6, static_cast<uint16_t>(data.size()));
  put16(d + 8, 0);
  std::memcpy(d + 10, data.data(), data.size());
  f.wkc_offset = 16 + 10 + data.size();
  return f;
}

// A captured frame: Ethernet header, EtherCAT header, datagrams (ETG.1000.4 §5.2, Table 11:
// length 11 bits, then 16-bit address words, length, IRQ, data, WKC).
bool load_frame(const std::string& path, const uint8_t* src_mac, Frame& f) {
  std::ifstream in(path, std::ios::binary);
  f.bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  if (f.bytes.size() < 14 + 2 + 12 || f.bytes[12] != (kEtherTypeEcat >> 8) ||
      f.bytes[13] != (kEtherTypeEcat & 0xFF)) {
    std::fprintf(stderr, "wire_pinger: %s: not an EtherCAT frame\n", path.c_str());
    return false;
  }
  const size_t data_len = get16(&f.bytes[16 + 6]) & 0x07FFu;
  f.wkc_offset = 16 + 10 + data_len;
  if (f.wkc_offset + 2 > f.bytes.size()) {
    std::fprintf(stderr, "wire_pinger: %s: first datagram runs past the frame\n", path.c_str());
    return false;
  }
  std::memcpy(&f.bytes[6], src_mac, 6);
  return true;
}

struct Socket {
  int fd = -1;
  uint8_t mac[6]{};
  bool busy = false;
};

// Sends a cycle's frames (datagram indexes index, index + 1, ...) one after the other, as a
// master does when its process image needs several frames, and waits for every reply. Returns
// the time until the last reply in ns, or -1 on timeout; `wkc_out` is the sum of the frames'
// first-datagram working counters.
int64_t round_trip(Socket& s, std::vector<Frame>& frames, uint8_t index, uint32_t& wkc_out) {
  static uint8_t rx[2048];
  const uint64_t t0 = now_ns();
  for (size_t k = 0; k < frames.size(); ++k) {
    frames[k].bytes[17] = static_cast<uint8_t>(index + k);
    if (send(s.fd, frames[k].bytes.data(), frames[k].bytes.size(), 0) < 0) return -1;
  }
  uint32_t wkc = 0;
  uint32_t answered = 0;  // bit k: frame k's reply came (at most kMaxFramesPerCycle frames)
  size_t pending = frames.size();
  while (pending > 0) {
    ssize_t n;
    if (s.busy) {
      n = recv(s.fd, rx, sizeof(rx), MSG_DONTWAIT);
      if (n < 0) {
        if (now_ns() - t0 > static_cast<uint64_t>(kTimeoutNs)) return -1;
        continue;
      }
    } else {
      const uint64_t elapsed = now_ns() - t0;
      if (elapsed > static_cast<uint64_t>(kTimeoutNs)) return -1;
      pollfd pfd{s.fd, POLLIN, 0};
      timespec left{0, static_cast<long>(kTimeoutNs - elapsed)};
      if (ppoll(&pfd, 1, &left, nullptr) <= 0) continue;
      n = recv(s.fd, rx, sizeof(rx), MSG_DONTWAIT);
      if (n < 0) continue;
    }
    // A reply: one of our frames with the ESC's source-MAC bit set and its datagram index.
    if (n < 18 || !(rx[6] & 0x02) || std::memcmp(rx + 7, s.mac + 1, 5) != 0) continue;
    const size_t k = static_cast<uint8_t>(rx[17] - index);
    if (k >= frames.size() || (answered & (1u << k)) != 0 ||
        n < static_cast<ssize_t>(frames[k].bytes.size())) {
      continue;
    }
    answered |= 1u << k;
    --pending;
    wkc += get16(rx + frames[k].wkc_offset);
  }
  wkc_out = wkc;
  return static_cast<int64_t>(now_ns() - t0);
}

// Waits until clock time `t` (now_ns's clock): spinning for a busy-poll pinger, else asleep.
void wait_until(uint64_t t, bool spin) {
  if (spin) {
    while (now_ns() < t) {
    }
    return;
  }
  const timespec ts{static_cast<time_t>(t / 1'000'000'000u), static_cast<long>(t % 1'000'000'000u)};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

double percentile(std::vector<int64_t>& v, double p) {
  if (v.empty()) return 0;
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(p / 100.0 * (v.size() - 1) + 0.5));
  std::nth_element(v.begin(), v.begin() + static_cast<long>(k), v.end());
  return static_cast<double>(v[k]) / 1000.0;
}

bool open_socket(const std::string& iface, Socket& s) {
  s.fd = socket(AF_PACKET, SOCK_RAW, 0);
  if (s.fd < 0) {
    std::fprintf(stderr, "wire_pinger: socket: %s\n", std::strerror(errno));
    return false;
  }
  ifreq ifr{};
  std::snprintf(ifr.ifr_name, sizeof(ifr.ifr_name), "%s", iface.c_str());
  if (ioctl(s.fd, SIOCGIFINDEX, &ifr) < 0) {
    std::fprintf(stderr, "wire_pinger: no such network interface: %s\n", iface.c_str());
    return false;
  }
  const int ifindex = ifr.ifr_ifindex;
  if (ioctl(s.fd, SIOCGIFHWADDR, &ifr) < 0) return false;
  std::memcpy(s.mac, ifr.ifr_hwaddr.sa_data, 6);
  int one = 1;
  (void)setsockopt(s.fd, SOL_PACKET, PACKET_IGNORE_OUTGOING, &one, sizeof(one));
  (void)setsockopt(s.fd, SOL_PACKET, PACKET_QDISC_BYPASS, &one, sizeof(one));
  sockaddr_ll addr{};
  addr.sll_family = AF_PACKET;
  addr.sll_protocol = htons(kEtherTypeEcat);
  addr.sll_ifindex = ifindex;
  if (bind(s.fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) < 0) {
    std::fprintf(stderr, "wire_pinger: bind: %s\n", std::strerror(errno));
    return false;
  }
  return true;
}

// FMMU0 (0x0600, ETG.1000.4 Table 57) of every slave: logical start, length, start bit 0,
// stop bit 7, physical 0x1000, physical start bit 0, type read+write (3), activate.
bool map_fmmus(Socket& s, int slaves, int lrw_bytes) {
  uint32_t wkc = 0;
  for (int pos = 0; pos < slaves; ++pos) {
    std::vector<uint8_t> fmmu(16, 0);
    put32(fmmu.data(), static_cast<uint32_t>(pos * lrw_bytes));
    put16(fmmu.data() + 4, static_cast<uint16_t>(lrw_bytes));
    fmmu[6] = 0;
    fmmu[7] = 7;
    put16(fmmu.data() + 8, 0x1000);
    fmmu[10] = 0;
    fmmu[11] = 3;
    fmmu[12] = 1;
    std::vector<Frame> f{build_frame(s.mac, kCmdApwr, static_cast<uint16_t>(-pos), 0x0600, fmmu)};
    // Idempotent register write: retried, so one late reply on a busy machine is no error.
    bool answered = false;
    for (int attempt = 0; attempt < 20 && !answered; ++attempt) {
      answered = round_trip(s, f, 0xF0, wkc) >= 0;
    }
    if (!answered) {
      std::fprintf(stderr, "wire_pinger: no answer to FMMU setup of slave %d\n", pos);
      return false;
    }
  }
  return true;
}

// split("a,b,c", ',') -> {"a", "b", "c"}; split("", ',') -> {""}.
std::vector<std::string> split(const std::string& list, char separator) {
  std::vector<std::string> parts;
  for (size_t pos = 0; pos <= list.size();) {
    const size_t end = std::min(list.find(separator, pos), list.size());
    parts.push_back(list.substr(pos, end - pos));
    pos = end + 1;
  }
  return parts;
}

}  // namespace

int main(int argc, char** argv) {
  std::string iface;
  std::string kind = "brd";
  int count = 10000;
  int warmup = 200;
  int slaves = 1;
  int lrw_bytes = 8;
  bool busy = false;
  bool setup_fmmu = false;
  std::string samples_out;
  std::string frame_file;
  long period_us = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string { return i + 1 < argc ? argv[++i] : ""; };
    if (a == "--iface")
      iface = next();
    else if (a == "--frame")
      kind = next();
    else if (a == "--count")
      count = std::atoi(next().c_str());
    else if (a == "--warmup")
      warmup = std::atoi(next().c_str());
    else if (a == "--slaves")
      slaves = std::atoi(next().c_str());
    else if (a == "--lrw-bytes")
      lrw_bytes = std::atoi(next().c_str());
    else if (a == "--busy-poll")
      busy = true;
    else if (a == "--setup-fmmu")
      setup_fmmu = true;
    else if (a == "--samples-out")
      samples_out = next();
    else if (a == "--frame-file")
      frame_file = next();
    else if (a == "--period-us")
      period_us = std::atol(next().c_str());
    else {
      std::fprintf(stderr, "wire_pinger: unknown argument %s\n", a.c_str());
      return 2;
    }
  }
  if (iface.empty() || (kind != "brd" && kind != "lrw") || count <= 0 || slaves <= 0 ||
      lrw_bytes <= 0 || lrw_bytes > 1024 || period_us < 0 || period_us > 1'000'000) {
    std::fprintf(stderr, "wire_pinger: bad arguments\n");
    return 2;
  }
  // One socket per interface; several interfaces are pinged in turn, frame by frame, so
  // that responders on them are measured under the same machine noise.
  const std::vector<std::string> ifaces = split(iface, ',');
  const std::vector<std::string> frame_files = split(frame_file, ',');
  if (frame_files.size() != 1 && frame_files.size() != ifaces.size()) {
    std::fprintf(stderr, "wire_pinger: --frame-file takes one file, or one per interface\n");
    return 2;
  }
  struct Target {
    Socket socket;
    std::vector<Frame> frames;  // one cycle: sent together, the round trip ends with the last reply
    std::vector<int64_t> samples;
    int lost = 0;
    uint32_t wkc = 0;
  };
  std::vector<Target> targets(ifaces.size());
  for (size_t k = 0; k < ifaces.size(); ++k) {
    Socket& s = targets[k].socket;
    s.busy = busy;
    if (!open_socket(ifaces[k], s)) return 2;
    if (setup_fmmu && !map_fmmus(s, slaves, lrw_bytes)) return 1;
    if (!frame_file.empty()) {
      const std::string& file = frame_files[frame_files.size() == 1 ? 0 : k];
      for (const std::string& part : split(file, '+')) {
        targets[k].frames.emplace_back();
        if (!load_frame(part, s.mac, targets[k].frames.back())) return 2;
      }
      if (targets[k].frames.size() > kMaxFramesPerCycle) {
        std::fprintf(stderr, "wire_pinger: at most %zu frames per cycle\n", kMaxFramesPerCycle);
        return 2;
      }
      kind = "file";
    } else {
      targets[k].frames.push_back(
          kind == "brd"
              ? build_frame(s.mac, kCmdBrd, 0, 0x0000, std::vector<uint8_t>(2, 0))
              : build_frame(s.mac, kCmdLrw, 0, 0,
                            std::vector<uint8_t>(static_cast<size_t>(lrw_bytes * slaves), 0x5A)));
    }
    targets[k].samples.reserve(static_cast<size_t>(count));
  }
  const uint64_t period_ns = static_cast<uint64_t>(period_us) * 1000u;
  uint64_t next_cycle = now_ns();
  for (int i = 0; i < warmup + count; ++i) {
    if (period_ns != 0) {
      wait_until(next_cycle, busy);
      next_cycle = std::max(next_cycle + period_ns, now_ns());
    }
    for (size_t j = 0; j < targets.size(); ++j) {
      // Alternate the order too, so no target always goes first after the other.
      Target& t = targets[(i % 2) ? targets.size() - 1 - j : j];
      // Each cycle's frames take consecutive datagram indexes below 0x80 (0xF0 is the FMMU
      // setup's), so a late reply of an earlier cycle is never taken for one of this cycle.
      const size_t per = t.frames.size();
      const auto index = static_cast<uint8_t>((static_cast<size_t>(i) % (0x80 / per)) * per);
      const int64_t rtt = round_trip(t.socket, t.frames, index, t.wkc);
      if (i < warmup) continue;
      if (rtt < 0) {
        ++t.lost;
        continue;
      }
      t.samples.push_back(rtt);
    }
  }
  for (size_t k = 0; k < targets.size(); ++k) {
    Target& t = targets[k];
    if (!samples_out.empty()) {
      const std::string path =
          targets.size() == 1 ? samples_out : samples_out + "." + std::to_string(k);
      FILE* out = std::fopen(path.c_str(), "w");
      if (out == nullptr) {
        std::fprintf(stderr, "wire_pinger: cannot write %s\n", path.c_str());
        return 2;
      }
      for (const int64_t v : t.samples) std::fprintf(out, "%lld\n", static_cast<long long>(v));
      std::fclose(out);
    }
    std::vector<int64_t> sorted = t.samples;
    std::sort(sorted.begin(), sorted.end());
    const double mn = sorted.empty() ? 0 : static_cast<double>(sorted.front()) / 1000.0;
    const double mx = sorted.empty() ? 0 : static_cast<double>(sorted.back()) / 1000.0;
    std::printf(
        "{\"iface\":\"%s\",\"frame\":\"%s\",\"count\":%zu,\"lost\":%d,\"p50_us\":%.2f,"
        "\"p90_us\":%.2f,\"p99_us\":%.2f,\"min_us\":%.2f,\"max_us\":%.2f,\"wkc\":%u}\n",
        ifaces[k].c_str(), kind.c_str(), sorted.size(), t.lost, percentile(sorted, 50),
        percentile(sorted, 90), percentile(sorted, 99), mn, mx, t.wkc);
    close(t.socket.fd);
  }
  return 0;
}
