// The logging side of `rackcat run` and `rackcat rim`: spdlog on stdout, as text or as JSON
// lines (--log-format json: one object per line with time, level, msg and the event's fields),
// at the level --log-level selects; and the thread that drains the event queue the cyclic path
// fills (base/event_log.hpp), turning each event into one log line: ESM transitions with the
// master's request and the AL status code with its ETG.1000.6 Table 11 name, refused requests
// with the reason, watchdog expiry, mailbox errors and SDO aborts (rate-limited at the source),
// RIM state changes, injected faults and parameter stores.
#pragma once

#include <CLI/CLI.hpp>
#include <atomic>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "base/event_log.hpp"

namespace rackcat::apps {

struct LogOptions {
  std::string level = "info";   // trace debug info warn error critical off
  std::string format = "text";  // text | json
};

// Adds --log-level and --log-format to a subcommand.
void add_log_options(CLI::App* cmd, LogOptions& options);

// Sets up spdlog's default logger (stdout) for `options`. Call before logging anything.
void configure_logging(const LogOptions& options);

// One log line for an event (the text, without time or level); level is set to the event's.
std::string describe_event(const base::Event& e, int& level, nlohmann::json& fields);

// Drains base::event_log() on its own thread from construction to destruction (which drains
// what is left). The queue is enabled only while it runs.
class EventLogger {
 public:
  EventLogger();
  ~EventLogger();
  EventLogger(const EventLogger&) = delete;
  EventLogger& operator=(const EventLogger&) = delete;

 private:
  void run();
  void drain();
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace rackcat::apps
