// What `rackcat run` does around the segment: open the raw-socket link on an interface and
// the optional capture file, give up root, then run the event loop that feeds every frame
// through Segment::process and fires the segment's SYNC/watchdog deadlines on time, until
// SIGINT or SIGTERM.
//
//   RunnerOptions options;                             // (designated initializers must name
//   options.interface_name = "eth1";                   //  every field under -Wextra)
//   options.wait = WaitMode::BusyPoll;
//   options.pcap_path = "x.pcap";
//   Runner runner(options);
//   if (int rc = runner.open("rackcat")) return rc;   // one-line error already printed
//   runner.loop().post(...);                           // e.g. from a control thread
//   return runner.run(segment);                        // 0 after SIGINT/SIGTERM
//
// The segment must use SteadyClock (CLOCK_MONOTONIC), the loop's time base.
#pragma once

#include <cstdio>
#include <memory>
#include <string>

#include "ecat/host/event_loop.hpp"
#include "ecat/host/pcap_writer.hpp"
#include "ecat/host/privileges.hpp"
#include "ecat/host/raw_socket_link.hpp"
#include "ecat/segment.hpp"

namespace rackcat::ecat {

struct RunnerOptions {
  std::string interface_name;
  WaitMode wait = WaitMode::Blocking;
  std::string pcap_path;  // empty: no capture
  // Privileges after the socket is open: all capabilities are dropped; `user` (name or uid)
  // or, under sudo, SUDO_UID becomes the process's user. drop_privileges = false keeps them
  // (debugging only).
  bool drop_privileges = true;
  std::string user;
  // EventLoop::Options::yield_window_ns for the slaves' firmware: 0 (default) finishes every
  // frame's firmware work before the next frame is answered; > 0 lets a frame that comes that
  // soon after the previous reply overtake it (lower latency for a master sending back to back;
  // a slave's inputs can then be a firmware round older: docs/PERFORMANCE.md, session 7).
  uint64_t firmware_yield_window_ns = 0;
};

// Exit codes shared with the CLI (apps/commands.hpp): 2 = the environment or the arguments
// are wrong (no such interface, no permission, unwritable capture file, unknown user).
inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;
inline constexpr int kExitUsage = 2;

class Runner {
 public:
  explicit Runner(RunnerOptions options);
  ~Runner();
  Runner(const Runner&) = delete;
  Runner& operator=(const Runner&) = delete;

  // Opens link and capture and drops privileges. Returns 0, or prints one line
  // "<program>: <reason>" to `err` and returns the exit code (2 for a missing interface,
  // missing permission, capture file or user problem). SIGINT/SIGTERM are caught from here on
  // and end run() cleanly, also when they arrive during start-up.
  int open(const char* program = "rackcat", FILE* err = stderr);

  // Runs the segment until SIGINT/SIGTERM or loop().stop(); returns 0 on a clean stop, 1 if
  // the loop failed. The capture is flushed before returning.
  int run(Segment& segment);

  EventLoop& loop() { return *loop_; }
  RawSocketLink& link() { return *link_; }
  PcapWriter* pcap() { return pcap_.get(); }
  const RunnerOptions& options() const { return options_; }
  const PrivilegeDropResult& privileges() const { return privileges_; }

 private:
  RunnerOptions options_;
  std::unique_ptr<RawSocketLink> link_;
  std::unique_ptr<PcapWriter> pcap_;
  std::unique_ptr<EventLoop> loop_;
  PrivilegeDropResult privileges_;
};

}  // namespace rackcat::ecat
