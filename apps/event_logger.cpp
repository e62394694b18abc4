#include "apps/event_logger.hpp"

#include <fmt/chrono.h>
#include <fmt/format.h>
#include <spdlog/pattern_formatter.h>
#include <spdlog/sinks/stdout_sinks.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <memory>
#include <string_view>

#include "base/esm_state.hpp"
#include "base/mailbox_error.hpp"
#include "base/real_time.hpp"
#include "coe/abort_code.hpp"
#include "ecat/al_status_code.hpp"

namespace rackcat::apps {
namespace {

// The fields of the event being logged on this thread, for the JSON-lines formatter.
thread_local const nlohmann::json* t_fields = nullptr;

// JSON lines: {"time": ISO 8601 UTC, "level", "msg", then the event's fields}.
class JsonLinesFormatter final : public spdlog::formatter {
 public:
  void format(const spdlog::details::log_msg& msg, spdlog::memory_buf_t& dest) override {
    nlohmann::json line;
    const auto t = msg.time.time_since_epoch();
    const auto secs = std::chrono::duration_cast<std::chrono::seconds>(t);
    const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(t - secs).count();
    line["time"] = fmt::format("{:%Y-%m-%dT%H:%M:%S}.{:03}Z",
                               fmt::gmtime(static_cast<std::time_t>(secs.count())), ms);
    const auto level = spdlog::level::to_string_view(msg.level);
    line["level"] = std::string(level.data(), level.size());
    line["msg"] = std::string(msg.payload.data(), msg.payload.size());
    if (t_fields) {
      for (const auto& [k, v] : t_fields->items()) line[k] = v;
    }
    const std::string text = line.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
    dest.append(text.data(), text.data() + text.size());
    dest.push_back('\n');
  }
  std::unique_ptr<spdlog::formatter> clone() const override {
    return std::make_unique<JsonLinesFormatter>();
  }
};

std::string_view rim_state_name(uint8_t s) {
  constexpr std::string_view kNames[] = {"OFFLINE", "CONNECTED", "ONLINE", "ERROR"};
  return s < 4 ? kNames[s] : "?";
}

std::string code_text(uint16_t code) {
  return fmt::format("0x{:04X} ({})", code, ecat::al_status_code_name(code));
}

}  // namespace

void add_log_options(CLI::App* cmd, LogOptions& options) {
  cmd->add_option("--log-level", options.level, "Log level (default info)")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "critical", "off"}));
  cmd->add_option("--log-format", options.format,
                  "text, or json: one JSON object per line (time, level, msg, event fields)")
      ->check(CLI::IsMember({"text", "json"}));
}

void configure_logging(const LogOptions& options) {
  auto logger = std::make_shared<spdlog::logger>("rackcat",
                                                 std::make_shared<spdlog::sinks::stdout_sink_mt>());
  if (options.format == "json") {
    logger->set_formatter(std::make_unique<JsonLinesFormatter>());
  } else {
    logger->set_pattern("%Y-%m-%d %H:%M:%S.%e %l: %v");
  }
  logger->set_level(spdlog::level::from_str(options.level));
  logger->flush_on(spdlog::level::trace);  // a log read while the slave runs (tests, demo)
  spdlog::set_default_logger(logger);
}

std::string describe_event(const base::Event& e, int& level, nlohmann::json& f) {
  using base::EventKind;
  level = spdlog::level::info;
  if (e.station != 0) f["station"] = e.station;
  switch (e.kind) {
    case EventKind::EsmTransition: {
      const uint8_t requested = e.c & 0x0F;
      f["event"] = "esm_transition";
      f["from"] = esm_state_name(e.a);
      f["to"] = esm_state_name(e.b);
      f["al_control"] = e.c;
      f["al_status_code"] = e.code;
      if (requested == e.b) {
        return fmt::format("ESM {} -> {} (master's AL control 0x{:02X})", esm_state_name(e.a),
                           esm_state_name(e.b), e.c);
      }
      level = spdlog::level::warn;
      return fmt::format("ESM {} -> {} on its own (master's AL control 0x{:02X} asks for {})",
                         esm_state_name(e.a), esm_state_name(e.b), e.c, esm_state_name(requested));
    }
    case EventKind::EsmError: {
      const uint8_t requested = e.c & 0x0F;
      f["event"] = "esm_error";
      f["from"] = esm_state_name(e.a);
      f["to"] = esm_state_name(e.b);
      f["al_control"] = e.c;
      f["al_status_code"] = e.code;
      f["al_status_name"] = ecat::al_status_code_name(e.code);
      level = spdlog::level::warn;
      if (e.a == e.b && requested != e.a) {
        f["event"] = "esm_refused";
        return fmt::format(
            "ESM refused {} -> {} requested by the master (AL control 0x{:02X}): "
            "AL status code {}; stays in {} with the error flag",
            esm_state_name(e.a), esm_state_name(requested), e.c, code_text(e.code),
            esm_state_name(e.a));
      }
      return fmt::format("ESM error in {}: AL status code {}; {} with the error flag",
                         esm_state_name(e.a), code_text(e.code),
                         e.a == e.b ? fmt::format("stays in {}", esm_state_name(e.b))
                                    : fmt::format("falls to {}", esm_state_name(e.b)));
    }
    case EventKind::WatchdogExpired:
      f["event"] = "watchdog_expired";
      f["state"] = esm_state_name(e.a);
      f["count"] = e.value;
      level = spdlog::level::warn;
      return fmt::format("process-data watchdog expired in {} (count {})", esm_state_name(e.a),
                         e.value);
    case EventKind::MailboxError:
      f["event"] = "mailbox_error";
      f["code"] = e.code;
      f["suppressed_before"] = e.suppressed;
      level = spdlog::level::warn;
      return fmt::format("mailbox error reply 0x{:04X} ({}){}", e.code,
                         mailbox::describe(static_cast<mailbox::Error>(e.code)),
                         e.suppressed ? fmt::format(" ({} more not logged)", e.suppressed) : "");
    case EventKind::SdoAbort:
      f["event"] = "sdo_abort";
      f["index"] = e.index;
      f["subindex"] = e.a;
      f["abort_code"] = e.value;
      f["suppressed_before"] = e.suppressed;
      return fmt::format("SDO abort 0x{:04X}:{:02X}: 0x{:08X} ({}){}", e.index, e.a, e.value,
                         coe::describe(static_cast<coe::AbortCode>(e.value)),
                         e.suppressed ? fmt::format(" ({} more not logged)", e.suppressed) : "");
    case EventKind::RimState:
      f["event"] = "rim_state";
      f["rim"] = e.a;
      f["from"] = rim_state_name(e.b);
      f["to"] = rim_state_name(e.c);
      f["comm_error"] = e.code != 0;
      if (e.c != 2) level = spdlog::level::warn;
      return fmt::format("RIM {} {} -> {}{}", e.a, rim_state_name(e.b), rim_state_name(e.c),
                         e.code ? " (communication error)" : "");
    case EventKind::FaultInjected: {
      f["event"] = "fault_injected";
      const auto what = static_cast<base::FaultWhat>(e.b);
      const std::string where =
          e.index ? fmt::format("module {} channel {}", e.index, e.a) : std::string();
      switch (what) {
        case base::FaultWhat::WiringFault:
          f["fault"] = "wiring_fault";
          // modules::WiringFault: 1 short to ground (safe), 2 short to supply (unsafe).
          f["value"] = e.value;
          return fmt::format("fault injected: {} wiring fault {}", where,
                             e.value == 0   ? "cleared"
                             : e.value == 1 ? "safe (short to ground)"
                             : e.value == 2 ? "unsafe (short to supply)"
                                            : fmt::format("{}", e.value));
        case base::FaultWhat::SensorOpen:
          f["fault"] = "sensor_open";
          return fmt::format("fault injected: {} sensor {}", where, e.value ? "open" : "closed");
        case base::FaultWhat::LoopOhms:
          f["fault"] = "loop_ohms";
          return fmt::format("fault injected: {} loop resistance {} ohm", where, e.value);
        case base::FaultWhat::FanRpm:
          f["fault"] = "fan_rpm";
          level = spdlog::level::debug;  // the CAN link reports fan speeds too
          return e.a ? fmt::format("RIM {} fan at {} rpm", e.a, e.value)
                     : fmt::format("CPU fan at {} rpm", e.value);
        case base::FaultWhat::McmErrors:
          f["fault"] = "mcm_errors";
          return fmt::format("fault injected: RIM {} MCM error bits 0x{:08X}", e.a, e.value);
        case base::FaultWhat::CpuTemperature:
          f["fault"] = "cpu_temperature";
          return fmt::format("fault injected: CPU temperature {:.1f} degC",
                             static_cast<int32_t>(e.value) / 10.0);
        case base::FaultWhat::Source:
          f["fault"] = "source";
          f["source"] = e.text.data();
          return fmt::format("{} source set to '{}'", where, e.text.data());
      }
      return "fault injected";
    }
    case EventKind::Store:
      f["event"] = "store";
      f["ok"] = e.code == 0;
      if (e.code != 0) level = spdlog::level::err;
      return fmt::format("{}: {}", e.text.data(), e.code == 0 ? "done" : "FAILED");
  }
  return "unknown event";
}

EventLogger::EventLogger() {
  base::event_log().enable(true);
  thread_ = std::thread([this] { run(); });
}

EventLogger::~EventLogger() {
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
  base::event_log().enable(false);
  try {
    drain();  // what is left; formatting can throw (bad_alloc), a destructor must not
  } catch (...) {
  }
}

void EventLogger::run() {
  (void)base::leave_real_time();  // a helper thread, not the device thread
  while (!stop_.load()) {
    drain();
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

void EventLogger::drain() {
  base::EventLog& log = base::event_log();
  base::Event e;
  while (log.pop(e)) {
    int level = 0;
    nlohmann::json fields = nlohmann::json::object();
    const std::string text = describe_event(e, level, fields);
    t_fields = &fields;
    const auto when = std::chrono::system_clock::time_point(
        std::chrono::duration_cast<std::chrono::system_clock::duration>(
            std::chrono::nanoseconds(e.time_ns)));
    spdlog::default_logger_raw()->log(when, spdlog::source_loc{},
                                      static_cast<spdlog::level::level_enum>(level), text);
    t_fields = nullptr;
  }
  if (const uint64_t lost = log.take_dropped()) {
    spdlog::warn("{} log event(s) lost: the event queue was full", lost);
  }
}

}  // namespace rackcat::apps
