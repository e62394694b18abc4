// `rackcat rim --can IFACE --rim N [--config FILE]`: one RIM of the rack file as its own
// process, a CANopen node (node-ID N) on a SocketCAN interface (docs/CAN.md): boot-up,
// heartbeat, SDO (identity, card list, CiA 401 objects), TPDOs with its input channels'
// sources, RPDOs to its outputs, until SIGINT/SIGTERM.
//
// `rackcat rim --can IFACE --watch [--rim N ...] [--config FILE]`: the control module's side
// without EtherCAT: checks and starts the RIMs and prints one line per RIM state change
// ("<ms since start> rim <N> <STATE> [comm-error] [reason]"), for tests and diagnosis.
#include <fmt/format.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "apps/commands.hpp"
#include "apps/rack_slave/rack_loading.hpp"
#include "mdp/rack_config.hpp"
#include "modules/canopen/socketcan.hpp"
#include "modules/rack/events.hpp"
#include "modules/rim/master.hpp"
#include "modules/rim/node.hpp"
#include "modules/rim/sources.hpp"

namespace rackcat::apps {
namespace {

using namespace modules::canopen;

std::atomic<bool> g_stop{false};
extern "C" void on_stop_signal(int) {
  g_stop.store(true);
}

struct RimArgs {
  std::string iface;
  std::vector<int> rims;
  std::string config;
  bool watch = false;
  int heartbeat_ms = 50;
  int heartbeat_timeout_ms = 150;
  int pdo_period_us = 1000;
  double duration_s = 0.0;  // 0 = until a signal
};

Micros now_us(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() -
                                                               t0)
      .count();
}

int run_rim(const RimArgs& a) {
  auto loaded = load_rack_or_report(a.config);
  if (!loaded) return 2;
  const mdp::RackConfig rack = std::move(*loaded);
  if (!a.watch && a.rims.size() != 1) {
    std::fprintf(stderr, "rackcat rim: give exactly one --rim N (or --watch)\n");
    return 2;
  }
  for (int r : a.rims) {
    if (r < 1 || r > 127 || !rack.rim(static_cast<uint8_t>(r))) {
      std::fprintf(stderr, "rackcat rim: %s has no RIM %d\n", rack.source.c_str(), r);
      return 2;
    }
  }
  std::unique_ptr<SocketCanBus> bus;
  try {
    bus = std::make_unique<SocketCanBus>(a.iface);
  } catch (const std::runtime_error& e) {
    std::fprintf(stderr, "rackcat rim: %s\n", e.what());
    return 1;
  }
  std::signal(SIGINT, on_stop_signal);
  std::signal(SIGTERM, on_stop_signal);
  const auto t0 = std::chrono::steady_clock::now();
  const Micros end = a.duration_s > 0 ? static_cast<Micros>(a.duration_s * 1e6) : -1;
  const Micros tick = std::max(100, a.pdo_period_us / 2);

  if (!a.watch) {
    RimNodeOptions o;
    o.heartbeat_period_us = Micros{a.heartbeat_ms} * 1000;
    o.pdo_period_us = a.pdo_period_us;
    std::unique_ptr<RimNode> node;
    try {
      node = std::make_unique<RimNode>(rack, static_cast<uint8_t>(a.rims[0]), *bus, o);
      apply_rack_sources(*node, rack);
    } catch (const mdp::ConfigError& e) {
      std::fprintf(stderr, "%s\n", e.what());
      return 2;
    }
    const RimProfile& p = node->profile();
    std::printf("RIM %d on %s: node-ID %d, %zu TPDO(s), %zu RPDO(s), heartbeat %d ms\n", a.rims[0],
                a.iface.c_str(), a.rims[0], p.tpdo_count(), p.rpdo_count(), a.heartbeat_ms);
    std::fflush(stdout);
    node->start(now_us(t0));
    while (!g_stop.load() && (end < 0 || now_us(t0) < end)) {
      bus->wait(tick);
      node->step(now_us(t0));
    }
    return 0;
  }

  RimMasterOptions o;
  o.heartbeat_timeout_us = Micros{a.heartbeat_timeout_ms} * 1000;
  o.pdo_period_us = a.pdo_period_us;
  std::vector<uint8_t> rims(a.rims.begin(), a.rims.end());
  RimMaster master(rack, *bus, o, rims);
  master.on_state([&](uint8_t rim, modules::RimState s, bool comm_error) {
    std::printf("%.1f rim %d %s%s%s%s\n", static_cast<double>(now_us(t0)) / 1000.0, rim,
                modules::rim_state_name(s).data(), comm_error ? " comm-error" : "",
                master.reason(rim).empty() ? "" : " ", master.reason(rim).c_str());
    std::fflush(stdout);
  });
  while (!g_stop.load() && (end < 0 || now_us(t0) < end)) {
    bus->wait(tick);
    master.step(now_us(t0));
  }
  const BusStatus& st = bus->status();
  std::printf("bus: %llu frames received, %llu sent, %llu dropped, %llu error frames\n",
              static_cast<unsigned long long>(st.rx_frames),
              static_cast<unsigned long long>(st.tx_frames),
              static_cast<unsigned long long>(st.tx_dropped),
              static_cast<unsigned long long>(st.error_frames));
  return 0;
}

void add_rim(CLI::App& app) {
  auto a = std::make_shared<RimArgs>();
  auto* cmd = app.add_subcommand(
      "rim", "Run one RIM as a CANopen node on a CAN interface (or --watch the RIMs)");
  cmd->add_option("--can", a->iface, "SocketCAN interface (vcan0, can0 ...)")->required();
  cmd->add_option("--rim", a->rims, "RIM number = node-ID (with --watch: RIMs to watch)");
  cmd->add_option("--config", a->config, "Rack file (YAML); default: the built-in rack");
  cmd->add_flag("--watch", a->watch, "Control-module side: check, start and watch the RIMs");
  cmd->add_option("--heartbeat-ms", a->heartbeat_ms, "Producer heartbeat time (0x1017)")
      ->check(CLI::Range(1, 65535));
  cmd->add_option("--heartbeat-timeout-ms", a->heartbeat_timeout_ms,
                  "--watch: heartbeat consumer time")
      ->check(CLI::Range(1, 65535));
  cmd->add_option("--pdo-period-us", a->pdo_period_us, "PDO cycle")
      ->check(CLI::Range(100, 1000000));
  cmd->add_option("--duration", a->duration_s, "Stop after this many seconds (0 = never)");
  cmd->callback([a] { exit_with(run_rim(*a)); });
}

const CommandRegistrar reg{"rim", add_rim};

}  // namespace
}  // namespace rackcat::apps
