// Where a wire round trip goes on the slave's side (docs/PERFORMANCE.md, "16 slaves,
// busy-poll"): `rackcat run`'s default racks behind a Segment on a raw socket, with the time of
// every Segment::process call and of every send call recorded separately. --echo answers like
// bench/ecat/echo_responder instead (source-MAC bit only), with the racks still built, so the
// two can be compared in the same placement.
//
//   wire_slave_timing --iface IFACE [--slaves N] [--echo] [--delay-ns D] [--busy-poll]
//                     [--state-dir DIR]
//
// Same command line shape as `rackcat run`, so scripts/wire_bench.py can start it with
// --slave-cmd. Runs until SIGINT/SIGTERM, then prints to stderr one line each for "process"
// and "send": count and p10/p50/p90/p99 in µs (first 1,048,576 frames). --delay-ns spins D ns
// after processing, to see how extra slave time shows up in the round trip. The slaves stay
// in whatever state the master brings them to; SYNC and watchdog deadlines are served as in
// ecat::EventLoop (busy-poll: clock check between receives; blocking: poll timeout).
#include <poll.h>
#include <algorithm>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <memory>
#include <string>
#include <vector>

#include "apps/rack_slave/rack_loading.hpp"
#include "apps/rack_slave/rack_slave.hpp"
#include "ecat/host/raw_socket_link.hpp"
#include "ecat/segment.hpp"

namespace {

volatile std::sig_atomic_t g_stop = 0;

uint64_t now_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<uint64_t>(ts.tv_sec) * 1'000'000'000ull + static_cast<uint64_t>(ts.tv_nsec);
}

void print_summary(const char* name, std::vector<uint32_t> v) {
  if (v.empty()) return;
  std::sort(v.begin(), v.end());
  auto at = [&v](size_t percent) { return v[v.size() * percent / 100] / 1e3; };
  std::fprintf(stderr, "%-7s n=%zu p10 %.2f p50 %.2f p90 %.2f p99 %.2f us\n", name, v.size(),
               at(10), at(50), at(90), at(99));
}

}  // namespace

int main(int argc, char** argv) {
  using namespace rackcat;
  std::string iface;
  std::string state_dir = "/tmp/wire_slave_timing";
  int slaves = 1;
  bool echo = false;
  bool busy = false;
  uint64_t delay_ns = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    if (a == "--iface" && has_value) {
      iface = argv[++i];
    } else if (a == "--slaves" && has_value) {
      slaves = std::max(1, std::atoi(argv[++i]));
    } else if (a == "--state-dir" && has_value) {
      state_dir = argv[++i];
    } else if (a == "--delay-ns" && has_value) {
      delay_ns = std::strtoull(argv[++i], nullptr, 10);
    } else if (a == "--echo") {
      echo = true;
    } else if (a == "--busy-poll") {
      busy = true;
    } else {
      std::fprintf(stderr,
                   "usage: %s --iface IFACE [--slaves N] [--echo] [--delay-ns D] [--busy-poll] "
                   "[--state-dir DIR]\n",
                   argv[0]);
      return 2;
    }
  }
  if (iface.empty()) {
    std::fprintf(stderr, "wire_slave_timing: --iface is required\n");
    return 2;
  }
  std::signal(SIGINT, [](int) { g_stop = 1; });
  std::signal(SIGTERM, [](int) { g_stop = 1; });

  const auto config = apps::load_rack_or_report("");
  if (!config) return 2;
  std::vector<std::unique_ptr<apps::RackSlave>> racks;
  std::vector<ecat::Application*> line;
  for (int i = 0; i < slaves; ++i) {
    racks.push_back(std::make_unique<apps::RackSlave>(*config, state_dir, i));
    line.push_back(racks.back().get());
  }
  ecat::Segment segment(line);
  std::unique_ptr<ecat::RawSocketLink> link;
  try {
    link = std::make_unique<ecat::RawSocketLink>(iface);
  } catch (const ecat::LinkError& e) {
    std::fprintf(stderr, "wire_slave_timing: %s\n", e.what());
    return 2;
  }

  constexpr size_t kMaxSamples = 1u << 20;
  std::vector<uint32_t> process_ns;
  std::vector<uint32_t> send_ns;
  process_ns.reserve(kMaxSamples);
  send_ns.reserve(kMaxSamples);
  uint64_t deadline = segment.next_event_bound_ns();
  pollfd pfd{link->fd(), POLLIN, 0};
  while (g_stop == 0) {
    if (!busy) {
      const uint64_t now = now_ns();
      const int timeout_ms = deadline == UINT64_MAX
                                 ? 100
                                 : static_cast<int>(std::min<uint64_t>(
                                       100, deadline > now ? (deadline - now) / 1'000'000 : 0));
      (void)::poll(&pfd, 1, timeout_ms);
    }
    const auto frame = link->try_receive();
    if (!frame.empty()) {
      const uint64_t t0 = now_ns();
      size_t reply = frame.size();
      if (echo) {
        frame[6] |= 0x02;
      } else {
        reply = segment.process(frame);
      }
      uint64_t t1 = now_ns();
      if (delay_ns != 0) {
        while (now_ns() < t0 + delay_ns) {
        }
        t1 = now_ns();
      }
      if (reply != 0) link->send(frame.first(reply));
      const uint64_t t2 = now_ns();
      if (process_ns.size() < kMaxSamples) {
        process_ns.push_back(static_cast<uint32_t>(t1 - t0));
        send_ns.push_back(static_cast<uint32_t>(t2 - t1));
      }
      if (!echo) segment.after_frame();  // the firmware, once the reply is out (as EventLoop)
      deadline = segment.next_event_bound_ns();
    }
    if (now_ns() >= deadline) {
      segment.service();
      deadline = segment.next_event_bound_ns();
    }
  }
  print_summary("process", std::move(process_ns));
  print_summary("send", std::move(send_ns));
  return 0;
}
