// The RIM link on a real kernel CAN stack (run by scripts/can_vm.sh inside a qemu VM, or
// natively where the kernel has AF_CAN and vcan0 exists): the control-module side (RimMaster)
// in this process, RIMs 1 and 2 of the default rack as `rackcat rim` processes on vcan0.
// Checks: both ONLINE; RIM 2 killed (SIGKILL) -> OFFLINE within the heartbeat consumer time
// while RIM 1 stays ONLINE; RIM 2 restarted -> ONLINE. Measures the age of RIM 1's input data
// as a 1 ms process-data cycle sees it, and the kill -> OFFLINE time. When `rackcat run` has
// --rim-bus, a second stage runs the EtherCAT slave with its RIMs on vcan0 (raw socket on lo,
// no master) and measures kill -> OFFLINE in 0x2rr1:08 through the control API. Prints one
// line:
//   CAN_VM_RESULT PASS|FAIL key=value ...
// Usage: can_vm_test RACKCAT_BINARY [IFACE]
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <httplib.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "mdp/rack_config.hpp"
#include "modules/canopen/socketcan.hpp"
#include "modules/control/control_api.hpp"
#include "modules/rim/master.hpp"
#include "tests/support/shell_quote.hpp"

using namespace rackcat;
using namespace rackcat::modules;
using namespace rackcat::modules::canopen;

namespace {

constexpr int kHeartbeatMs = 50;
constexpr int kHeartbeatTimeoutMs = 150;

const auto t0 = std::chrono::steady_clock::now();
Micros now_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() -
                                                               t0)
      .count();
}

pid_t spawn_rim(const std::string& rackcat, const std::string& iface, int rim) {
  const pid_t pid = fork();
  if (pid == 0) {
    const std::string r = std::to_string(rim);
    const std::string hb = std::to_string(kHeartbeatMs);
    execl(rackcat.c_str(), rackcat.c_str(), "rim", "--can", iface.c_str(), "--rim", r.c_str(),
          "--heartbeat-ms", hb.c_str(), static_cast<char*>(nullptr));
    std::perror("exec rackcat");
    _exit(127);
  }
  return pid;
}

[[noreturn]] void result(bool pass, const std::string& text, std::vector<pid_t> children) {
  for (pid_t p : children) {
    if (p > 0) {
      kill(p, SIGKILL);
      waitpid(p, nullptr, 0);
    }
  }
  std::printf("CAN_VM_RESULT %s %s\n", pass ? "PASS" : "FAIL", text.c_str());
  std::fflush(stdout);
  std::exit(pass ? 0 : 1);
}

// Does this rackcat's `run` know --rim-bus?
bool has_rim_bus(const std::string& rackcat) {
  const std::string cmd = rackcat::testing::shell_quote(rackcat) + " run --help 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return false;
  std::string out;
  char buf[512];
  for (size_t n; (n = fread(buf, 1, sizeof buf, p)) > 0;) out.append(buf, n);
  pclose(p);
  return out.find("--rim-bus") != std::string::npos;
}

// The control API's per-run secret, which `rackcat run` writes into its state directory at
// start; empty until the file is there. Every request must carry it as a bearer token.
std::string control_token(const std::string& state_dir) {
  FILE* f = std::fopen((state_dir + "/" + modules::kTokenFileName).c_str(), "r");
  if (!f) return {};
  char buf[256] = {};
  const bool ok = std::fgets(buf, sizeof buf, f) != nullptr;
  std::fclose(f);
  if (!ok) return {};
  std::string token(buf);
  while (!token.empty() && (token.back() == '\n' || token.back() == '\r')) token.pop_back();
  return token;
}

// The RIM states `rackcat run` shows in 0x2rr1:08 (control API /api/exceptions): rim -> state.
std::map<int, std::string> rim_states(httplib::Client& cli, const std::string& state_dir) {
  std::map<int, std::string> out;
  const std::string token = control_token(state_dir);
  if (token.empty()) return out;
  cli.set_bearer_token_auth(token);
  auto res = cli.Get("/api/exceptions");
  if (!res || res->status != 200) return out;
  const auto j = nlohmann::json::parse(res->body, nullptr, false);
  if (j.is_discarded() || !j.contains("rims")) return out;
  for (const auto& r : j["rims"]) out[r.value("rim", 0)] = r.value("state", "");
  return out;
}

// Stage 2: `rackcat run --iface lo --rim-bus can:IFACE` with RIMs 1 and 2 as processes; kill
// RIM 2 and time OFFLINE in 0x2rr1:08, restart it and wait for ONLINE.
bool run_stage(const std::string& rackcat, const std::string& iface, std::string& text) {
  static constexpr const char* kStateDir = "/tmp/rackcat-state";
  const pid_t run = fork();
  if (run == 0) {
    const std::string bus = "can:" + iface;
    execl(rackcat.c_str(), rackcat.c_str(), "run", "--iface", "lo", "--rim-bus", bus.c_str(),
          "--no-pty", "--control-port", "8765", "--state-dir", kStateDir,
          static_cast<char*>(nullptr));
    std::perror("exec rackcat run");
    _exit(127);
  }
  pid_t rim1 = spawn_rim(rackcat, iface, 1);
  pid_t rim2 = spawn_rim(rackcat, iface, 2);
  httplib::Client cli("127.0.0.1", 8765);
  cli.set_connection_timeout(0, 200000);
  cli.set_read_timeout(1, 0);
  auto state_of = [&](int rim) {
    const auto s = rim_states(cli, kStateDir);
    const auto it = s.find(rim);
    return it == s.end() ? std::string("?") : it->second;
  };
  auto wait_for = [&](int rim, const char* state, Micros limit) {
    const Micros end = now_us() + limit;
    while (now_us() < end) {
      if (state_of(rim) == state) return true;
      usleep(2000);
    }
    return false;
  };
  auto finish = [&](bool ok, std::string t) {
    for (pid_t p : {rim1, rim2, run}) {
      if (p > 0) {
        kill(p, SIGKILL);
        waitpid(p, nullptr, 0);
      }
    }
    text = std::move(t);
    return ok;
  };
  if (!wait_for(1, "online", 15'000'000) || !wait_for(2, "online", 5'000'000)) {
    return finish(false, "run_stage=start_failed rim1=" + state_of(1) + " rim2=" + state_of(2));
  }
  const Micros killed = now_us();
  kill(rim2, SIGKILL);
  waitpid(rim2, nullptr, 0);
  rim2 = -1;
  if (!wait_for(2, "offline", 2'000'000)) return finish(false, "run_stage=no_offline");
  const double offline_ms = (now_us() - killed) / 1000.0;
  const bool rim1_online = state_of(1) == "online";
  const Micros restarted = now_us();
  rim2 = spawn_rim(rackcat, iface, 2);
  if (!wait_for(2, "online", 10'000'000)) return finish(false, "run_stage=no_online_again");
  const double online_ms = (now_us() - restarted) / 1000.0;
  char t[256];
  std::snprintf(t, sizeof t,
                "run_kill_to_offline_0x2rr1_ms=%.1f run_restart_to_online_ms=%.1f "
                "run_rim1_stayed_online=%d",
                offline_ms, online_ms, rim1_online ? 1 : 0);
  // The API is polled every 2 ms through HTTP: allow 50 ms on top of the heartbeat bound.
  return finish(rim1_online && offline_ms <= kHeartbeatTimeoutMs + kHeartbeatMs + 50, t);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: can_vm_test RACKCAT_BINARY [IFACE]\n");
    return 2;
  }
  const std::string rackcat = argv[1];
  const std::string iface = argc > 2 ? argv[2] : "vcan0";
  const mdp::RackConfig rack = mdp::default_rack();
  std::unique_ptr<SocketCanBus> bus;
  try {
    bus = std::make_unique<SocketCanBus>(iface);
  } catch (const std::exception& e) {
    result(false, std::string("reason=\"") + e.what() + "\"", {});
  }
  RimMasterOptions o;
  o.heartbeat_timeout_us = Micros{kHeartbeatTimeoutMs} * 1000;
  RimMaster master(rack, *bus, o, {1, 2});
  Micros offline_at = -1;
  master.on_state([&](uint8_t rim, RimState s, bool) {
    if (rim == 2 && s == RimState::Offline && offline_at < 0) offline_at = now_us();
  });

  pid_t rim1 = spawn_rim(rackcat, iface, 1);
  pid_t rim2 = spawn_rim(rackcat, iface, 2);
  auto run_until = [&](auto done, Micros limit) {
    const Micros end = now_us() + limit;
    while (!done() && now_us() < end) {
      bus->wait(200);
      master.step(now_us());
    }
    return done();
  };
  auto both_online = [&] {
    return master.state(1) == RimState::Online && master.state(2) == RimState::Online;
  };
  const Micros boot_start = now_us();
  if (!run_until(both_online, 10'000'000)) {
    result(false, "stage=start rim1=\"" + master.reason(1) + "\" rim2=\"" + master.reason(2) + "\"",
           {rim1, rim2});
  }
  const double start_ms = (now_us() - boot_start) / 1000.0;

  // Input data age seen by a 1 ms process-data cycle: at each cycle, how old is the newest
  // TPDO data of RIM 1.
  std::vector<double> ages;
  Micros next_cycle = now_us();
  while (ages.size() < 2000) {
    bus->wait(100);
    const Micros t = now_us();
    master.step(t);
    if (t >= next_cycle) {
      ages.push_back((t - master.last_input_time(1)) / 1000.0);
      next_cycle += 1000;
    }
  }
  std::sort(ages.begin(), ages.end());
  double sum = 0;
  for (double a : ages) sum += a;
  const double age_mean = sum / ages.size();
  const double age_p99 = ages[ages.size() * 99 / 100];
  const double age_max = ages.back();

  // Unplug RIM 2.
  const Micros killed = now_us();
  kill(rim2, SIGKILL);
  waitpid(rim2, nullptr, 0);
  rim2 = -1;
  if (!run_until([&] { return master.state(2) == RimState::Offline; }, 2'000'000)) {
    result(false, "stage=kill state2=" + std::to_string(int(master.state(2))), {rim1});
  }
  const double offline_ms = (offline_at - killed) / 1000.0;
  if (master.state(1) != RimState::Online) {
    result(false, "stage=kill rim1_not_online", {rim1});
  }
  // Replug.
  const Micros restarted = now_us();
  rim2 = spawn_rim(rackcat, iface, 2);
  if (!run_until(both_online, 10'000'000)) {
    result(false, "stage=restart rim2=\"" + master.reason(2) + "\"", {rim1, rim2});
  }
  const double online_ms = (now_us() - restarted) / 1000.0;
  const bool in_time = offline_ms <= kHeartbeatTimeoutMs + kHeartbeatMs;
  char text[512];
  std::snprintf(text, sizeof text,
                "start_ms=%.1f kill_to_offline_ms=%.1f restart_to_online_ms=%.1f "
                "input_age_mean_ms=%.3f input_age_p99_ms=%.3f input_age_max_ms=%.3f "
                "heartbeat_ms=%d consumer_ms=%d error_frames=%llu",
                start_ms, offline_ms, online_ms, age_mean, age_p99, age_max, kHeartbeatMs,
                kHeartbeatTimeoutMs, static_cast<unsigned long long>(bus->status().error_frames));
  std::string line = text;
  kill(rim1, SIGKILL);
  kill(rim2, SIGKILL);
  waitpid(rim1, nullptr, 0);
  waitpid(rim2, nullptr, 0);
  bus.reset();  // the stage-1 control module leaves the bus
  bool pass = in_time;
  if (has_rim_bus(rackcat)) {
    std::string stage2;
    pass = run_stage(rackcat, iface, stage2) && pass;
    line += " " + stage2;
  } else {
    line += " run_stage=skipped";
  }
  result(pass, line, {});
}
