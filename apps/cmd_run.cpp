// `rackcat run`: the emulated rack(s) on a network interface, answering a real master.
//
//   rackcat run --iface IFACE [--config FILE] [--slaves N | --line FILE | --eni FILE --esi-dir DIR]
//               [--busy-poll] [--firmware-yield-us N] [--pcap FILE]
//               [--state-dir DIR] [--control-port P] [--user USER] [--rim-bus can:IFACE]
//               [--pdi direct|lan9252-emulated]
//
// Parses the rack file, opens the raw socket (needs CAP_NET_RAW) and the capture file, drops
// every privilege while the process still has a single thread (capabilities are per thread),
// then, as the unprivileged user, opens the state directory and builds N racks from the
// configuration (each its own ESC, object dictionary, drivers, stored parameters and
// parameter worker thread; channel sources read their files now), starts the control API on
// 127.0.0.1 and the UART pseudo-terminals, and runs until SIGINT or SIGTERM, then exits 0. A
// bad configuration is one line "FILE:LINE: problem" and exit 2 (a bad channel source is
// found once the racks are built, after the interface is opened); a missing interface or
// permission is one line and exit 2.
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <memory>
#include <mutex>
#include <optional>
#include <stop_token>
#include <string>
#include <thread>
#include <vector>

#include <spdlog/spdlog.h>

#include "apps/commands.hpp"
#include "apps/event_logger.hpp"
#include "apps/line/io_device_adapter.hpp"
#include "apps/line/line_loading.hpp"
#include "apps/rack_slave/rack_loading.hpp"
#include "apps/rack_slave/rack_slave.hpp"
#include "apps/slave_link.hpp"
#include "base/real_time.hpp"
#include "device/foe_files.hpp"
#include "device/generic_device.hpp"
#include "ecat/host/huge_heap.hpp"
#include "ecat/host/runner.hpp"
#include "ecat/segment.hpp"
#include "mdp/file_root.hpp"
#include "mdp/rack_config.hpp"
#include "mdp/state_directory.hpp"
#include "mdp/sync_manager_layout.hpp"
#include "modules/canopen/socketcan.hpp"
#include "modules/control/control_api.hpp"
#include "modules/rim/threaded_link.hpp"

namespace rackcat::apps {
namespace {

struct RunArgs {
  std::string iface;
  std::string config;
  int slaves = 1;
  bool busy_poll = false;
  uint32_t firmware_yield_us = 0;
  std::string huge_heap = "auto";  // on, off, auto: from kHugeHeapSlaves slaves on
  std::string pcap;
  std::string state_dir;
  int control_port = modules::kDefaultControlPort;
  bool no_control = false;
  bool no_ptys = false;
  std::string user;
  std::string data_dir;  // replay files named by control-API requests are read below it
  std::string rim_bus;   // "can:IFACE": RIMs are CANopen nodes on that bus (docs/CAN.md)
  uint16_t boot_mailbox_size = mdp::sm::kBootMailboxSize;
  std::optional<uint32_t> foe_password;
  LogOptions log;
  LineSource line;  // a line file or an ENI (docs/LINE.md): ESI devices and racks in order
  // How the firmware reaches each ESC: the chip model's PDI, or through the LAN9252 host-bus
  // protocol (docs/ESC.md "The LAN9252 backend").
  std::string pdi = "direct";
};

// Lines from this size on put their heap in huge pages by default (--huge-heap auto): at 1,024
// tiny racks a cycle took 5-10 % less on the wire and 10 % less in process; at 199 and 256 no
// gain showed and the heap's free holes cost 2-9 KiB per slave (docs/PERFORMANCE.md, session 18).
// Since the heap grows in 2 MiB steps (grow_heap_in_huge_page_steps) the gain on the wire at
// 1,024 is 0-5 % for 0.4-0.5 MiB (session 19).
constexpr size_t kHugeHeapSlaves = 512;

void heap_in_huge_pages(const std::string& mode, size_t slaves) {
  if (mode == "off" || (mode == "auto" && slaves < kHugeHeapSlaves)) return;
  const ecat::HugeHeapResult h = ecat::advise_huge_heap();
  if (h.advised_bytes != 0) {
    spdlog::info("rackcat: heap in huge pages: {} MiB{}", h.advised_bytes >> 20,
                 h.collapsed ? "" : " (advised; the kernel collapses them in the background)");
  } else {
    spdlog::info("rackcat: heap stays in 4 KiB pages: {}",
                 h.error != 0 ? std::strerror(h.error) : "no whole 2 MiB range");
  }
}

int run(const RunArgs& a) {
  // The configuration first: a bad file must not need a network interface to be reported.
  std::vector<std::unique_ptr<RackSlave>> racks;
  const std::string state_dir = a.state_dir.empty() ? mdp::default_state_dir() : a.state_dir;
  configure_logging(a.log);
  // Before anything of the line is allocated (ecat/host/huge_heap.hpp: a long line's cycle is a
  // quarter faster for it).
  if (!ecat::grow_heap_in_huge_page_steps()) {
    spdlog::debug("rackcat: malloc keeps its default heap growth (no M_TOP_PAD)");
  }
  std::optional<mdp::RackConfig> config;
  std::optional<LineFile> line_file;
  if (!a.line.line.empty() || !a.line.eni.empty()) {
    line_file = load_line_or_report(a.line);
    if (!line_file) return ecat::kExitUsage;
    for (auto& d : line_file->devices) {
      if (!d.rack) continue;
      d.rack->control.boot_mailbox_size = a.boot_mailbox_size;
      if (a.foe_password) d.rack->control.foe_password = *a.foe_password;
    }
  } else {
    config = load_rack_or_report(a.config);
    if (!config) return ecat::kExitUsage;
    config->control.boot_mailbox_size = a.boot_mailbox_size;
    if (a.foe_password) config->control.foe_password = *a.foe_password;
  }

  // Socket and capture file first, then the drop, before any thread exists.
  ecat::Runner runner({.interface_name = a.iface,
                       .wait = a.busy_poll ? ecat::WaitMode::BusyPoll : ecat::WaitMode::Blocking,
                       .pcap_path = a.pcap,
                       .drop_privileges = true,
                       .user = a.user,
                       .firmware_yield_window_ns = a.firmware_yield_us * 1'000ull});
  if (const int rc = runner.open("rackcat"); rc != 0) return rc;

  // From here on everything runs as the unprivileged user: the state directory and the files
  // channel sources name are opened with its rights.
  const auto state = mdp::StateDirectory::open(state_dir);
  if (!state->usable()) spdlog::warn("rackcat: {}", state->problem());
  std::vector<ecat::Application*> line;
  std::vector<size_t> rack_position;  // line position of racks[i]
  // FoE files of ESI devices whose ESI announces FoE (docs/LINE.md "FoE"): declared before
  // the devices, which refer to them, so they outlive them.
  std::vector<std::unique_ptr<device::FoeFiles>> foe_files;
  std::vector<std::unique_ptr<device::GenericDevice>> generics;
  std::vector<modules::ControlSlave> controlled;  // the control API's slaves, in line order
  std::vector<std::unique_ptr<GenericIoDevice>> io_devices;
  // Every slave keeps its state directory open (mdp::StateDirectory holds a descriptor): with
  // thousands of slaves the default soft limit of 1024 descriptors is too low. Raise the soft
  // limit as far as the hard limit allows (no privilege needed).
  if (rlimit files{}; getrlimit(RLIMIT_NOFILE, &files) == 0) {
    const rlim_t wanted = static_cast<rlim_t>(a.slaves) + 256;
    if (files.rlim_cur < wanted) {
      files.rlim_cur = std::min(files.rlim_max, wanted);
      (void)setrlimit(RLIMIT_NOFILE, &files);
    }
  }
  try {
    // Channel sources of the rack file are parsed by the drivers: their errors are
    // configuration errors too (FILE:LINE).
    if (line_file) {
      std::vector<device::GenericDevice*> at(line_file->devices.size(), nullptr);
      for (size_t i = 0; i < line_file->devices.size(); ++i) {
        auto& d = line_file->devices[i];
        if (d.esi) {
          generics.push_back(std::make_unique<device::GenericDevice>(std::move(*d.esi)));
          if (generics.back()->esi().description.foe) {
            // Its own file directory beneath the state directory, by line position.
            foe_files.push_back(std::make_unique<device::FoeFiles>(
                state->fd(), "esi-" + std::to_string(i),
                a.foe_password.value_or(mdp::ControlModule{}.foe_password)));
            if (!foe_files.back()->usable())
              spdlog::warn(
                  "rackcat: slave {}: FoE directory {}/esi-{} unusable; FoE requests "
                  "are refused",
                  i, state_dir, i);
            generics.back()->serve_foe(*foe_files.back(),
                                       {.max_name_length = 64,
                                        .max_file_size = device::FoeFiles::kMaxFileBytes,
                                        .transfer_timeout_ms = 10'000});
          }
          at[i] = generics.back().get();
          line.push_back(generics.back().get());
          io_devices.push_back(std::make_unique<GenericIoDevice>(*generics.back()));
          controlled.push_back({nullptr, io_devices.back().get()});
        } else {
          racks.push_back(
              std::make_unique<RackSlave>(*d.rack, state, static_cast<int>(racks.size())));
          rack_position.push_back(i);
          line.push_back(racks.back().get());
          controlled.push_back({&racks.back()->rack(), nullptr});
        }
      }
      for (const auto& w : line_file->wiring)
        at[w.to]->add_wire(*at[w.from], w.from_bit, w.to_bit, w.bits);
      // Signal sources on ESI devices' inputs, sampled every cycle at the time since start.
      const auto start = std::chrono::steady_clock::now();
      for (size_t i = 0; i < line_file->devices.size(); ++i) {
        for (const auto& in : line_file->devices[i].inputs) {
          at[i]->add_input_driver(in.bit, in.bits, [in, start] {
            const std::chrono::duration<double> t = std::chrono::steady_clock::now() - start;
            return in.code(in.source->sample(t.count()));
          });
        }
      }
    } else {
      for (int i = 0; i < a.slaves; ++i) {
        racks.push_back(std::make_unique<RackSlave>(*config, state, i));
        rack_position.push_back(static_cast<size_t>(i));
        line.push_back(racks.back().get());
        controlled.push_back({&racks.back()->rack(), nullptr});
      }
    }
  } catch (const mdp::ConfigError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return ecat::kExitUsage;
  }
  ecat::SegmentOptions segment_options;
  if (a.pdi == "lan9252-emulated") segment_options.pdi = ecat::PdiAccess::Lan9252Emulated;
  ecat::Segment segment(line, ecat::SteadyClock::instance(), segment_options);

  // A rack that must leave OP (a RIM lost with Detect Modules Override 0) asks the firmware through
  // the loop, after the current frame, like a local application error (ETG.1000.6 §5.3.3).
  for (size_t r = 0; r < racks.size(); ++r) {
    const size_t i = rack_position[r];
    racks[r]->rack().set_state_request_handler([&runner, &segment, i](EsmState to, uint16_t code) {
      runner.loop().post(
          [&segment, i, to, code] { segment.slave(i).firmware().application_error(to, code); });
    });
  }

  // 0xFBF0 device reset: the rack restarts its firmware too (back to INIT, no error). The
  // restarted firmware first stores the SII image of the version that runs now into the ESC's
  // EEPROM (word 0x0C revision; ecat/slave/eeprom_store.cpp), so the master's next scan reads it.
  for (size_t r = 0; r < racks.size(); ++r) {
    const size_t i = rack_position[r];
    RackSlave* slave = racks[r].get();
    racks[r]->set_restart_handler([&runner, &segment, i, slave] {
      runner.loop().post([&segment, i, slave] {
        slave->finish_device_reset();
        segment.slave(i).firmware().store_eeprom();
        segment.slave(i).firmware().application_restart();
      });
    });
  }

  // From here on the cyclic path reports its events; this thread writes them (base/event_log).
  const EventLogger event_logger;
  if (line_file) {
    spdlog::info("rackcat: line {}: {} slave(s) on {} ({})", line_file->file, line.size(), a.iface,
                 a.busy_poll ? "busy-poll" : "blocking");
    size_t g = 0, r = 0;
    for (size_t i = 0; i < line_file->devices.size(); ++i) {
      if (r < rack_position.size() && rack_position[r] == i) {
        spdlog::info("rackcat: slave {}: rack {}", i, racks[r]->device().config().source);
        ++r;
      } else {
        const auto& d = generics[g++]->esi().description;
        spdlog::info("rackcat: slave {}: {} ({})", i, d.device_name, d.order_code);
      }
    }
  } else {
    const auto& cfg = racks.front()->device().config();
    spdlog::info("rackcat: {} slave(s) on {} ({}), rack {}: {} RIM(s), {} module(s)", a.slaves,
                 a.iface, a.busy_poll ? "busy-poll" : "blocking", cfg.source, cfg.rims.size(),
                 cfg.modules.size());
    spdlog::info("rackcat: state directory {}; {}; {}", state_dir,
                 racks.front()->device().load_report(), racks.front()->device().firmware_report());
    for (size_t i = 1; i < racks.size(); ++i) {
      spdlog::info("rackcat: slave {}: {}", i, racks[i]->device().load_report());
    }
  }
  if (!a.no_ptys && !racks.empty()) racks.front()->rack().start_uart_ptys();
  // The control API of every slave (docs/MODULES.md "Control API"): a fresh secret in the state
  // directory (mode 0600, this user's), the port exclusively ours, and where ctl finds both.
  std::unique_ptr<modules::ControlApi> api;
  if (!a.no_control) {
    modules::ControlApiOptions options;
    try {
      options.token = modules::ControlApi::new_token();
      if (!a.data_dir.empty()) options.data = mdp::FileRoot::open(a.data_dir);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "rackcat: --data-dir: %s\n", e.what());
      return ecat::kExitUsage;
    }
    options.link = slave_link(segment, runner.loop());
    api = std::make_unique<modules::ControlApi>(
        controlled, [&runner](std::function<void()> f) { runner.loop().post(std::move(f)); },
        options);
    uint16_t port = 0;
    try {
      port = api->listen(static_cast<uint16_t>(a.control_port));
    } catch (const std::exception& e) {
      std::fprintf(stderr, "rackcat: %s (is another rackcat running?)\n", e.what());
      return ecat::kExitUsage;
    }
    std::string error;
    const std::string token_line = options.token + "\n";
    const std::string port_line = std::to_string(port) + "\n";
    if (!state->replace(modules::kTokenFileName,
                        {reinterpret_cast<const uint8_t*>(token_line.data()), token_line.size()},
                        0600, error) ||
        !state->replace(modules::kPortFileName,
                        {reinterpret_cast<const uint8_t*>(port_line.data()), port_line.size()},
                        0644, error)) {
      std::fprintf(stderr, "rackcat: control API not started: %s\n", error.c_str());
      return ecat::kExitUsage;
    }
    spdlog::info("rackcat: control API on http://127.0.0.1:{} (token in {}/{})", port, state_dir,
                 modules::kTokenFileName);
    // The web page's login URL carries the secret: printed once, on stdout only, never logged.
    std::printf("rackcat: web page: %s\n", api->login_url().c_str());
    std::fflush(stdout);
  }
  // RIMs on a CAN bus (docs/CAN.md): slave 0's rack follows their heartbeats and PDOs.
  std::unique_ptr<modules::canopen::ThreadedRimLink> rim_link;
  if (!a.rim_bus.empty()) {
    if (racks.empty()) {
      std::fprintf(stderr, "rackcat: --rim-bus needs a rack in the line\n");
      return ecat::kExitUsage;
    }
    try {
      rim_link = std::make_unique<modules::canopen::ThreadedRimLink>(
          racks.front()->rack(),
          std::make_unique<modules::canopen::SocketCanBus>(a.rim_bus.substr(4)),
          modules::canopen::RimMasterOptions{}, std::vector<uint8_t>{},
          [&runner](std::function<void()> f) { runner.loop().post(std::move(f)); });
    } catch (const std::exception& e) {
      std::fprintf(stderr, "rackcat: --rim-bus %s: %s\n", a.rim_bus.c_str(), e.what());
      return ecat::kExitUsage;
    }
    spdlog::info("rackcat: RIMs on CAN interface {}", a.rim_bus.substr(4));
  }
  // The racks' own clock (guide §4.8: 0x2000:0F every 30 s in every ESM state, with or without
  // process data): once a second on the loop thread.
  std::jthread clock_thread([&runner, &racks](const std::stop_token& stop) {
    (void)base::leave_real_time();  // a helper thread, not the device thread
    std::mutex m;
    std::condition_variable_any cv;
    std::unique_lock lock(m);
    while (!stop.stop_requested()) {
      cv.wait_for(lock, stop, std::chrono::seconds(1), [] { return false; });
      if (stop.stop_requested()) break;
      runner.loop().post([&racks] {
        for (auto& r : racks) r->rack().on_clock();
      });
    }
  });
  std::fflush(stdout);
  if (!a.pcap.empty()) spdlog::info("rackcat: capturing to {}", a.pcap);
  heap_in_huge_pages(a.huge_heap, line.size());

  const int rc = runner.run(segment);
  spdlog::info("rackcat: stopped; {} frames received, {} sent", runner.link().frames_received(),
               runner.link().frames_sent());
  return rc;
}

void add_run(CLI::App& app) {
  auto args = std::make_shared<RunArgs>();
  CLI::App* cmd = app.add_subcommand("run", "Run the emulated rack(s) on a network interface");
  cmd->add_option("--iface", args->iface, "network interface to answer EtherCAT frames on")
      ->required();
  auto* config = cmd->add_option("--config", args->config,
                                 "rack configuration (YAML); default: built-in rack");
  auto* slaves = cmd->add_option("--slaves", args->slaves, "number of slaves in the segment")
                     ->check(CLI::Range(1, 4096));
  auto* line = cmd->add_option("--line", args->line.line,
                               "line file (YAML): ESI devices and racks in order (docs/LINE.md)");
  line->excludes(slaves);
  line->excludes(config);
  auto* eni = cmd->add_option("--eni", args->line.eni,
                              "ENI file (ETG.2100): the line a configuration tool exported");
  auto* esi_dir = cmd->add_option("--esi-dir", args->line.esi_dir,
                                  "directory of the ESI (and rack) files the ENI's devices are "
                                  "looked up in by identity");
  eni->needs(esi_dir);
  esi_dir->needs(eni);
  eni->excludes(slaves);
  eni->excludes(config);
  eni->excludes(line);
  cmd->add_flag("--busy-poll", args->busy_poll, "spin on the socket instead of blocking");
  cmd->add_option(
         "--firmware-yield-us", args->firmware_yield_us,
         "let a frame that comes within this many us of the previous reply be answered "
         "before the slaves' firmware has finished the previous frame's work (back-to-back "
         "masters: lower latency, inputs up to one firmware round old); 0 = off")
      ->check(CLI::Range(0, 1000));
  cmd->add_option("--huge-heap", args->huge_heap,
                  "the line's heap in 2 MiB pages once built (fewer TLB misses a cycle; free heap "
                  "holes become resident): on, off, or auto (lines of " +
                      std::to_string(kHugeHeapSlaves) + " slaves or more)")
      ->check(CLI::IsMember({"auto", "on", "off"}));
  cmd->add_option("--pcap", args->pcap, "record every frame in and out to this pcap file");
  cmd->add_option("--state-dir", args->state_dir,
                  "where stored parameters live (default $XDG_STATE_HOME/rackcat)");
  cmd->add_option("--control-port", args->control_port,
                  "control API port on 127.0.0.1 (0 = any free port)")
      ->check(CLI::Range(0, 65535));
  cmd->add_flag("--no-control", args->no_control, "do not start the control API");
  cmd->add_option("--data-dir", args->data_dir,
                  "directory below which the control API reads replay files (default: none)");
  cmd->add_flag("--no-pty", args->no_ptys, "do not create UART pseudo-terminals");
  cmd->add_option("--user", args->user, "user to run as once the socket is open");
  cmd->add_option("--pdi", args->pdi, "firmware-to-ESC access: direct or lan9252-emulated")
      ->check(CLI::IsMember({"direct", "lan9252-emulated"}));
  cmd->add_option("--rim-bus", args->rim_bus,
                  "can:IFACE: the RIMs are CANopen nodes on this SocketCAN interface "
                  "(`rackcat rim`); default: in-process")
      ->check([](const std::string& v) {
        return v.rfind("can:", 0) == 0 && v.size() > 4 ? std::string()
                                                       : std::string("expected can:IFACE");
      });
  cmd->add_option("--boot-mailbox-size", args->boot_mailbox_size,
                  "bytes of the bootstrap mailbox SM0 and SM1 (BOOT state, FoE); default 512")
      ->check(CLI::Range(mdp::sm::kMinMailboxSize, mdp::sm::kMaxMailboxSize));
  cmd->add_option("--foe-password", args->foe_password,
                  "password FoE requests must carry (UINT32, 0x.. accepted; docs/FOE.md)");
  add_log_options(cmd, args->log);
  cmd->callback([args] { exit_with(run(*args)); });
}

const CommandRegistrar registrar{"run", add_run};

}  // namespace
}  // namespace rackcat::apps
