// ecat_wire_slave: a segment of N emulated slaves with a fixed test device (hand-built SII,
// outputs looped back to inputs) on a network interface, for testing the ESC, the link and
// real masters on the wire before the real device exists.
//
//   ecat_wire_slave --iface IFACE [--slaves N] [--busy-poll] [--pcap FILE] [--user USER]
//   ecat_wire_slave --print-sii [--position K]      # the EEPROM image of slave K, hex
//
// Runs until SIGINT/SIGTERM and exits 0, printing what the applications saw (SYNC0 pulses,
// output updates, watchdog expiries). A missing interface or permission: one line, exit 2.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "ecat/host/runner.hpp"
#include "ecat/segment.hpp"
#include "tests/ecat_wire_slave/loopback_application.hpp"

namespace {

using rackcat::tests::LoopbackApplication;
using rackcat::tests::TestSiiIdentity;

TestSiiIdentity identity_at(int position) {
  TestSiiIdentity id;
  id.serial = static_cast<uint32_t>(position + 1);
  return id;
}

// How regularly SYNC0 reached the application: the deviation of each interval between two
// pulses from the programmed cycle (the median interval), in µs. Coalesced pulses (a loop that
// was descheduled) show up as intervals of several cycles.
void print_sync_jitter(const std::vector<uint64_t>& times) {
  if (times.size() < 3) return;
  std::vector<uint64_t> intervals;
  for (size_t i = 1; i < times.size(); ++i) intervals.push_back(times[i] - times[i - 1]);
  std::vector<uint64_t> sorted = intervals;
  std::sort(sorted.begin(), sorted.end());
  const uint64_t cycle = sorted[sorted.size() / 2];
  std::vector<uint64_t> dev;
  for (uint64_t v : intervals) dev.push_back(v > cycle ? v - cycle : cycle - v);
  std::sort(dev.begin(), dev.end());
  auto pct = [&](double p) {
    return static_cast<double>(dev[static_cast<size_t>(p * static_cast<double>(dev.size() - 1))]) /
           1000.0;
  };
  std::printf(
      "sync0 jitter (slave 0): cycle %.1f us, deviation p50 %.1f us, p99 %.1f us, max %.1f us"
      " over %zu intervals\n",
      static_cast<double>(cycle) / 1000.0, pct(0.5), pct(0.99), pct(1.0), dev.size());
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"ecat_wire_slave: N emulated EtherCAT slaves with a loopback test device"};
  std::string iface;
  int slaves = 1;
  bool busy_poll = false;
  std::string pcap;
  std::string user;
  bool print_sii = false;
  int position = 0;
  app.add_option("--iface", iface, "network interface to answer on");
  app.add_option("--slaves", slaves, "number of slaves in the segment")->check(CLI::Range(1, 256));
  app.add_flag("--busy-poll", busy_poll, "spin on the socket instead of blocking");
  app.add_option("--pcap", pcap, "record every frame in and out to this pcap file");
  app.add_option("--user", user, "user to run as after opening the socket");
  app.add_flag("--print-sii", print_sii, "print the SII EEPROM image (hex) and exit");
  app.add_option("--position", position, "slave position for --print-sii")
      ->check(CLI::Range(0, 255));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);
    return rc == 0 ? 0 : 2;
  }

  if (print_sii) {
    for (uint8_t b : rackcat::tests::build_test_sii(identity_at(position))) std::printf("%02x", b);
    std::printf("\n");
    return 0;
  }
  if (iface.empty()) {
    std::fprintf(stderr, "ecat_wire_slave: --iface is required\n");
    return 2;
  }

  rackcat::ecat::Runner runner(
      {.interface_name = iface,
       .wait = busy_poll ? rackcat::ecat::WaitMode::BusyPoll : rackcat::ecat::WaitMode::Blocking,
       .pcap_path = pcap,
       .drop_privileges = true,
       .user = user});
  if (const int rc = runner.open("ecat_wire_slave"); rc != 0) return rc;

  std::vector<std::unique_ptr<LoopbackApplication>> apps;
  std::vector<rackcat::ecat::Application*> line;
  for (int i = 0; i < slaves; ++i) {
    apps.push_back(std::make_unique<LoopbackApplication>(identity_at(i)));
    line.push_back(apps.back().get());
  }
  rackcat::ecat::Segment segment(line);
  std::printf("ecat_wire_slave: %d slave(s) on %s, %s%s%s\n", slaves, iface.c_str(),
              busy_poll ? "busy-poll" : "blocking", pcap.empty() ? "" : ", capture ", pcap.c_str());
  std::fflush(stdout);

  const int rc = runner.run(segment);

  std::printf("ecat_wire_slave: stopped (%s); %llu frames received, %llu sent\n",
              runner.loop().stop_signal() != 0 ? "signal" : "stop",
              static_cast<unsigned long long>(runner.link().frames_received()),
              static_cast<unsigned long long>(runner.link().frames_sent()));
  std::printf("sync0 events:");
  for (const auto& a : apps)
    std::printf(" %llu", static_cast<unsigned long long>(a->sync0_events()));
  std::printf("\noutputs received:");
  for (const auto& a : apps) {
    std::printf(" %llu", static_cast<unsigned long long>(a->outputs_received()));
  }
  std::printf("\nwatchdog expiries:");
  for (const auto& a : apps) {
    std::printf(" %llu", static_cast<unsigned long long>(a->watchdog_expiries()));
  }
  std::printf("\n");
  print_sync_jitter(apps.front()->sync0_times());
  return rc;
}
