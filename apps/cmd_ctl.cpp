// `rackcat ctl [--port P] [--json] <command>`: the client of a running rack's fault-injection
// control API (modules/control/control_api.hpp, HTTP + JSON on 127.0.0.1). Every command prints
// the rack's state after the request as text, or the API's JSON answer with --json (before or
// after the command name); an invalid request prints the API's reason and exits 2, an
// unreachable rack exits 1.
#include <httplib.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "apps/commands.hpp"
#include "mdp/device.hpp"
#include "mdp/state_directory.hpp"
#include "modules/control/control_api.hpp"

namespace rackcat::apps {
namespace {

using json = nlohmann::json;

struct CtlOptions {
  int port = 0;  // 0: the port `rackcat run` recorded in the state directory, else 8765
  std::string state_dir;
  std::string token_file;
  int slave = 0;
  bool json_output = false;
  int module = 0;
  int channel = 0;
  int rim = 0;
  double value = 0.0;
  std::optional<double> value_opt;
  std::string source;
  std::vector<std::string> params;
  bool comm_error = false;
  std::string state;
  std::string zone;
  double rpm = 0.0;
  double celsius = 0.0;
  bool now = false;
  std::string fault;
  std::optional<int64_t> encoder_steps;
  bool encoder_clear = false;
  bool open = false;
  bool close = false;
  std::optional<double> loop_ohms;
  std::string text;
  std::string hex;
  std::string error;
  std::string cts;
  std::string overload;
  std::string overtemperature;
  int bit = 0;
  std::optional<int> bits;
};

// The first line of a small file below the state directory (no symlink followed), or "".
std::string first_line(const std::string& dir, const char* name) {
  const auto state = mdp::StateDirectory::open(dir);
  std::vector<uint8_t> bytes;
  std::string why;
  if (state->read(name, 4096, bytes, why) != mdp::StateDirectory::ReadResult::Ok) return {};
  std::string text(bytes.begin(), bytes.end());
  return text.substr(0, text.find('\n'));
}

std::string read_token_file(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  return line;
}

using Printer = void (*)(const json&);

[[noreturn]] void request(const CtlOptions& o, const std::string& method,
                          const std::string& api_path, const json& body, Printer print) {
  // The rack's secret and port: where `rackcat run` wrote them (docs/MODULES.md "Control API").
  const std::string dir = o.state_dir.empty() ? mdp::default_state_dir() : o.state_dir;
  int port = o.port;
  if (port == 0) {
    const std::string recorded = first_line(dir, modules::kPortFileName);
    port = recorded.empty() ? modules::kDefaultControlPort : std::atoi(recorded.c_str());
  }
  const std::string token = o.token_file.empty() ? first_line(dir, modules::kTokenFileName)
                                                 : read_token_file(o.token_file);
  if (token.empty()) {
    std::fprintf(stderr,
                 "rackcat ctl: no control token in %s; give --state-dir (as for `rackcat "
                 "run`) or --token-file\n",
                 o.token_file.empty() ? (dir + "/" + modules::kTokenFileName).c_str()
                                      : o.token_file.c_str());
    exit_with(2);
  }
  const std::string path =
      o.slave == 0 ? api_path : "/api/slaves/" + std::to_string(o.slave) + api_path.substr(4);
  httplib::Client cli("127.0.0.1", port);
  cli.set_connection_timeout(2, 0);
  cli.set_read_timeout(5, 0);
  cli.set_bearer_token_auth(token.c_str());
  auto res = method == "GET" ? cli.Get(path.c_str())
                             : cli.Post(path.c_str(), body.dump(), "application/json");
  if (!res) {
    std::fprintf(stderr,
                 "rackcat ctl: no rack answers on 127.0.0.1:%d (%s); is `rackcat run` running "
                 "with its control API?\n",
                 port, httplib::to_string(res.error()).c_str());
    exit_with(1);
  }
  const json answer = json::parse(res->body, nullptr, false);
  if (res->status >= 400) {
    const std::string reason = answer.is_object() && answer.contains("error")
                                   ? answer["error"].get<std::string>()
                                   : res->body;
    std::fprintf(stderr, "rackcat ctl: %s\n", reason.c_str());
    exit_with(res->status >= 500 ? 1 : 2);
  }
  if (o.json_output || answer.is_discarded()) {
    std::printf("%s", res->body.c_str());
  } else {
    try {
      print(answer);
    } catch (const json::exception& e) {
      // An answer of another shape (a newer rack): show it as it came rather than half a table.
      std::fprintf(stderr, "rackcat ctl: unexpected answer (%s); as received:\n", e.what());
      std::printf("%s", res->body.c_str());
    }
  }
  exit_with(0);
}

void print_module(const json& m) {
  std::printf("module %3d  RIM %d slot %2d  %-9s %s\n", m["module"].get<int>(), m["rim"].get<int>(),
              m["slot"].get<int>(), m["card"].get<std::string>().c_str(),
              m["description"].get<std::string>().c_str());
  for (const auto& c : m["outputs"]) {
    std::printf("    out%-2d driven %-8g wire %-8g code 0x%04X %s%s\n", c["channel"].get<int>(),
                c["driven"].get<double>(), c["wire"].get<double>(), c["code"].get<unsigned>(),
                c["unit"].get<std::string>().c_str(),
                c.contains("wiring_fault") && c["wiring_fault"] != "none"
                    ? ("  wiring fault: " + c["wiring_fault"].get<std::string>()).c_str()
                    : "");
  }
  for (const auto& c : m["inputs"]) {
    std::printf("    in%-3d %-10.4g %-5s code 0x%04X  %s%s\n", c["channel"].get<int>(),
                c["value"].get<double>(), c["unit"].get<std::string>().c_str(),
                c["code"].get<unsigned>(), c["source"].get<std::string>().c_str(),
                c.value("open", false) ? "  OPEN" : "");
  }
  if (m.contains("uart")) {
    for (const auto& u : m["uart"]) {
      std::printf(
          "    uart%d %-12s %6d Bd %d%c%d  status %s  errors %s\n", u["channel"].get<int>(),
          u["pty"].get<std::string>().empty() ? "(no pty)" : u["pty"].get<std::string>().c_str(),
          u["baud"].get<int>(), u["data_bits"].get<int>(),
          u["parity"] == "none" ? 'N' : (u["parity"] == "even" ? 'E' : 'O'),
          u["stop_bits"].get<int>(), u["status"].get<std::string>().c_str(),
          u["errors"].get<std::string>().c_str());
    }
  }
}

// A RIM's two fan zones: "power supply 3000, slot card none" (rpm, or none where it has none).
std::string rim_fans(const json& rim) {
  auto zone = [&](const char* has, const char* rpm) {
    return rim[has].get<bool>() ? std::to_string(rim[rpm].get<int>()) : std::string("none");
  };
  return "power supply " + zone("power_supply_fan", "power_supply_rpm") + ", slot card " +
         zone("slot_card_fan", "slot_card_rpm");
}

void print_rack(const json& r) {
  std::printf(
      "ESM %s  outputs %s  detect modules override %d  CPU %.1f degC (published %.1f)  "
      "CPU fan %.0f rpm\n",
      r["esm"].get<std::string>().c_str(), r["outputs_valid"].get<bool>() ? "valid" : "not driven",
      r["detect_modules_override"].get<bool>() ? 1 : 0, r["cpu_temperature"].get<double>(),
      r["cpu_temperature_published"].get<double>(), r["cpu_fan_rpm"].get<double>());
  for (const auto& rim : r["rims"]) {
    std::printf(
        "RIM %d %s%s  fans: %s\n", rim["rim"].get<int>(), rim["state"].get<std::string>().c_str(),
        rim["comm_error"].get<bool>() ? " (communication error)" : "", rim_fans(rim).c_str());
  }
  for (const auto& m : r["modules"]) print_module(m);
}

// `rackcat ctl diag`: the 0x10F3 history as text, oldest first (ETG.1020 ch. 13).
void print_diagnosis(const json& d) {
  std::printf(
      "0x10F3: %zu of %d messages, newest %d, newest acknowledged %d, %s mode, flags %s%s\n",
      d["messages"].size(), d["maximum_messages"].get<int>(), d["newest_message"].get<int>(),
      d["newest_acknowledged"].get<int>(), d["mode"].get<std::string>().c_str(),
      d["flags"].get<std::string>().c_str(),
      d["new_messages_available"].get<bool>() ? ", new messages" : "");
  for (const auto& m : d["messages"]) {
    const uint64_t ns = m["time_ns"].get<uint64_t>();
    std::printf("  %3d %c %-7s %s %s %10llu.%06llu s %s  %s\n", m["subindex"].get<int>(),
                m["acknowledged"].get<bool>() ? '+' : ' ', m["type"].get<std::string>().c_str(),
                m["text_id"].get<std::string>().c_str(), m["diag_code"].get<std::string>().c_str(),
                static_cast<unsigned long long>(ns / 1000000000ull),
                static_cast<unsigned long long>((ns / 1000ull) % 1000000ull),
                m["time_base"].get<std::string>().c_str(), m["text"].get<std::string>().c_str());
  }
}

// `rackcat ctl esm`.
void print_esm(const json& e) {
  std::printf("ESM %s  outputs %s  detect modules override %d\n",
              e["state"].get<std::string>().c_str(),
              e["outputs_valid"].get<bool>() ? "valid" : "not driven",
              e["detect_modules_override"].get<bool>() ? 1 : 0);
}

// The exception tree (guide §3.4: 0xF380 summary, 0xF382/0xF384 per module, 0xF386/0xF388
// global, 0xF39x their latched copies) and each RIM's state; the answer of every command that
// changes a fault.
void print_exceptions(const json& t) {
  std::printf("0xF380 summary %s (latched 0xF390 %s)  device event status %s\n",
              t["F380"].get<std::string>().c_str(), t["F390"].get<std::string>().c_str(),
              t["device_event_status"].get<std::string>().c_str());
  std::printf("global warnings 0xF386:01 %s  errors 0xF388:01 %s  (latched %s / %s)\n",
              t["F386"].get<std::string>().c_str(), t["F388"].get<std::string>().c_str(),
              t["F396"].get<std::string>().c_str(), t["F398"].get<std::string>().c_str());
  for (const auto& rim : t["rims"]) {
    std::printf("RIM %d %-9s event status %s\n", rim["rim"].get<int>(),
                rim["state"].get<std::string>().c_str(),
                rim["event_status"].get<std::string>().c_str());
  }
  if (t["modules"].empty()) std::printf("no module warnings or errors\n");
  for (const auto& m : t["modules"]) {
    std::printf("module %3d  warnings 0xF382 %s  errors 0xF384 %s  (latched %s / %s)\n",
                m["module"].get<int>(), m["F382"].get<std::string>().c_str(),
                m["F384"].get<std::string>().c_str(), m["F392"].get<std::string>().c_str(),
                m["F394"].get<std::string>().c_str());
  }
}

// `rackcat ctl cpu-temp`: the zone temperature and what 0x2000:0F publishes (guide §4.8).
void print_cpu_temperature(const json& c) {
  std::printf("CPU temperature %.1f degC, 0x2000:0F publishes %.1f degC\n",
              c["cpu_temperature"].get<double>(), c["published"].get<double>());
}

// `rackcat ctl uart`: the module after the injection and how many bytes its receive ring took.
void print_uart(const json& m) {
  print_module(m);
  std::printf("accepted %d bytes\n", m["accepted"].get<int>());
}

// `rackcat ctl wiring-fault` / `fan`: the module or fan after the change, then the tree.
// A device of a line built from its ESI (GET /api/io, docs/LINE.md "Control").
void print_io(const json& a) {
  std::printf("slave %d: %s\n  outputs (%d bits): %s\n  inputs  (%d bits): %s\n",
              a.value("slave", 0), a.value("device", "").c_str(), a.value("output_bits", 0),
              a.value("outputs", "").c_str(), a.value("input_bits", 0),
              a.value("inputs", "").c_str());
}

void print_fault_answer(const json& a) {
  if (a.contains("module_state")) print_module(a["module_state"]);
  if (a.contains("fans")) {
    const json& f = a["fans"];
    std::printf("CPU fan %.0f rpm\n", f["cpu_fan_rpm"].get<double>());
    for (const auto& rim : f["rims"]) {
      std::printf("RIM %d fans: %s\n", rim["rim"].get<int>(), rim_fans(rim).c_str());
    }
  }
  print_exceptions(a);
}

// Every command takes --json, so `rackcat ctl --json X` and `rackcat ctl X --json` both work.
CLI::App* command(CLI::App* ctl, const std::shared_ptr<CtlOptions>& o, const char* name,
                  const char* description) {
  CLI::App* c = ctl->add_subcommand(name, description);
  c->add_flag("--json", o->json_output, "print the API's JSON answer instead of text");
  return c;
}

void add_ctl(CLI::App& app) {
  auto o = std::make_shared<CtlOptions>();
  CLI::App* ctl = app.add_subcommand(
      "ctl",
      "inspect a running rack and inject faults through its control API (127.0.0.1); prints the "
      "state after each request as text, or the API's JSON with --json");
  ctl->add_option("--port", o->port,
                  "control API port (default: the one `rackcat run` recorded, else 8765)");
  ctl->add_option("--state-dir", o->state_dir,
                  "state directory of the rack (default $XDG_STATE_HOME/rackcat): its "
                  "control-token and control-port files");
  ctl->add_option("--token-file", o->token_file, "read the control token from this file");
  ctl->add_option("--slave", o->slave, "slave of the segment (0-based)")->check(CLI::Range(0, 255));
  ctl->add_flag("--json", o->json_output, "print the API's JSON answer instead of text");
  ctl->require_subcommand(1);

  CLI::App* list = command(ctl, o, "list", "RIMs, modules and channels with live values");
  list->add_option("--module", o->module, "only this module (1..255)");
  list->callback([o] {
    if (o->module > 0)
      request(*o, "GET", "/api/modules/" + std::to_string(o->module), {}, print_module);
    request(*o, "GET", "/api/rack", {}, print_rack);
  });

  command(ctl, o, "esm", "the EtherCAT state and whether outputs are driven")->callback([o] {
    request(*o, "GET", "/api/esm", {}, print_esm);
  });
  command(ctl, o, "exceptions", "event status and the exception tree 0xF380..0xF398")
      ->callback([o] { request(*o, "GET", "/api/exceptions", {}, print_exceptions); });

  CLI::App* set = command(ctl, o, "set", "set an input channel's value or signal source");
  set->add_option("--module", o->module, "module number")->required();
  set->add_option("--channel", o->channel, "input channel (0-based)")->required();
  auto* value = set->add_option("--value", o->value_opt, "a constant value (V, degC or 0/1)");
  auto* source = set->add_option(
      "--source", o->source,
      "constant (value), ramp (from, to, period_s), sine (amplitude, frequency or period_s, "
      "offset, phase), noise (mean, stddev, seed), replay (file, loop), loopback (module or "
      "rim+slot, channel, gain, offset), plant (plant, a, b, c, d, x0, inputs, output) or "
      "clock (tick_us); parameters with --param");
  value->excludes(source);
  set->add_option(
         "--param", o->params,
         "source parameter key=value (repeatable); also the channel options loop_ohms=OHMS "
         "(thermocouple) and open=true|false (thermocouple, RTD)")
      ->needs(source);
  set->callback([o] {
    json body{{"module", o->module}, {"channel", o->channel}};
    if (o->value_opt) {
      body["value"] = *o->value_opt;
    } else if (!o->source.empty()) {
      body["source"] = o->source;
      json p = json::object();
      for (const std::string& kv : o->params) {
        const auto eq = kv.find('=');
        if (eq == std::string::npos || eq == 0) {
          std::fprintf(stderr, "rackcat ctl: --param needs key=value, got '%s'\n", kv.c_str());
          exit_with(2);
        }
        p[kv.substr(0, eq)] = kv.substr(eq + 1);
      }
      body["params"] = p;
    } else {
      std::fprintf(stderr, "rackcat ctl set: give --value or --source\n");
      exit_with(2);
    }
    request(*o, "POST", "/api/channel", body, print_module);
  });

  CLI::App* unplug = command(ctl, o, "unplug", "take a RIM offline (cable pulled)");
  unplug->add_option("--rim", o->rim, "RIM number 1..5")->required();
  unplug->add_flag("--comm-error", o->comm_error, "offline through a communication error");
  unplug->callback([o] {
    request(*o, "POST", "/api/rim/unplug", {{"rim", o->rim}, {"comm_error", o->comm_error}},
            print_exceptions);
  });
  CLI::App* replug = command(ctl, o, "replug", "bring a RIM back online");
  replug->add_option("--rim", o->rim, "RIM number 1..5")->required();
  replug->callback([o] {
    request(*o, "POST", "/api/rim/replug", {{"rim", o->rim}}, print_exceptions);
  });
  CLI::App* rim_state = command(ctl, o, "rim-state", "set a RIM's communication state");
  rim_state->add_option("--rim", o->rim, "RIM number 1..5")->required();
  rim_state->add_option("--state", o->state, "offline, connected, online or error")->required();
  rim_state->add_flag("--comm-error", o->comm_error, "with a communication error");
  rim_state->callback([o] {
    request(*o, "POST", "/api/rim/state",
            {{"rim", o->rim}, {"state", o->state}, {"comm_error", o->comm_error}},
            print_exceptions);
  });

  CLI::App* mcm = command(ctl, o, "mcm-error", "set a RIM's safety-controller errors");
  mcm->add_option("--rim", o->rim, "RIM number 1..5")->required();
  mcm->add_option("--error", o->params,
                  "slot_machine_mcm0, sout_compare_mcm0, slot_machine_mcm1, sout_compare_mcm1 "
                  "(repeatable; none given = all cleared)");
  mcm->callback([o] {
    request(*o, "POST", "/api/rim/mcm", {{"rim", o->rim}, {"errors", o->params}}, print_exceptions);
  });

  CLI::App* fan = command(ctl, o, "fan", "set a fan's RPM (nominal 3000)");
  fan->add_option("--rim", o->rim, "RIM number, 0 = control module CPU fan")->required();
  fan->add_option("--zone", o->zone, "cpu, power_supply or slot_card");
  fan->add_option("--rpm", o->rpm, "revolutions per minute")->required();
  fan->callback([o] {
    json body{{"rim", o->rim}, {"rpm", o->rpm}};
    if (!o->zone.empty()) body["zone"] = o->zone;
    request(*o, "POST", "/api/fan", body, print_fault_answer);
  });

  CLI::App* cpu = command(ctl, o, "cpu-temp", "set the CPU zone temperature (0x2000:0F)");
  cpu->add_option("--celsius", o->celsius, "degrees Celsius")->required();
  cpu->add_flag("--now", o->now, "publish now instead of at the next 30 s update");
  cpu->callback([o] {
    request(*o, "POST", "/api/cpu_temperature", {{"celsius", o->celsius}, {"immediate", o->now}},
            print_cpu_temperature);
  });

  CLI::App* dg =
      command(ctl, o, "diag", "the diagnosis history 0x10F3 as text (ETG.1020; + = acknowledged)");
  dg->callback([o] { request(*o, "GET", "/api/diagnosis", {}, print_diagnosis); });

  // A device of the line built from its ESI (docs/LINE.md "Control"): its process data.
  CLI::App* io = command(
      ctl, o, "io", "outputs (read back) and inputs of a device from its ESI, as hex (--slave N)");
  io->callback([o] { request(*o, "GET", "/api/io", {}, print_io); });
  CLI::App* si =
      command(ctl, o, "set-inputs",
              "set input bits of a device from its ESI (--slave N): HEX [--bit B --bits N]");
  si->add_option("HEX", o->hex, "the bits, LSB first, as hex bytes (e.g. A5)")->required();
  si->add_option("--bit", o->bit, "first input bit (default 0)")->check(CLI::Range(0, 65535));
  si->add_option("--bits", o->bits, "how many bits (default: all of HEX)")
      ->check(CLI::Range(1, 8192));
  si->callback([o] {
    json body{{"data", o->hex}, {"bit", o->bit}};
    if (o->bits) body["bits"] = *o->bits;
    request(*o, "POST", "/api/io/inputs", body, print_io);
  });

  CLI::App* of = command(ctl, o, "output-fault", "overload / overtemperature of an output");
  of->add_option("--module", o->module, "module number")->required();
  of->add_option("--channel", o->channel, "output channel (0-based)")->required();
  of->add_option("--overload", o->overload, "true or false");
  of->add_option("--overtemperature", o->overtemperature, "true or false");
  of->callback([o] {
    json body{{"module", o->module}, {"channel", o->channel}};
    for (const auto& [key, v] :
         {std::pair<const char*, const std::string*>{"overload", &o->overload},
          {"overtemperature", &o->overtemperature}}) {
      if (v->empty()) continue;
      if (*v != "true" && *v != "false") {
        std::fprintf(stderr, "rackcat ctl output-fault: --%s must be true or false\n", key);
        exit_with(2);
      }
      body[key] = *v == "true";
    }
    request(*o, "POST", "/api/output_fault", body, print_diagnosis);
  });

  CLI::App* ef = command(ctl, o, "encoder-fault",
                         "encoder card fault: hardware error, position jump, frozen position");
  ef->add_option("--module", o->module, "module number")->required();
  ef->add_option("--fault", o->fault, "hardware, jump or frozen")->required();
  ef->add_option("--steps", o->encoder_steps, "physical steps a jump adds (default 1000)");
  ef->add_flag("--clear", o->encoder_clear, "remove the fault instead");
  ef->callback([o] {
    json body{{"module", o->module}, {"fault", o->fault}, {"active", !o->encoder_clear}};
    if (o->encoder_steps) body["steps"] = *o->encoder_steps;
    request(*o, "POST", "/api/encoder_fault", body, print_diagnosis);
  });

  CLI::App* wf = command(ctl, o, "wiring-fault", "force a wiring fault on a sourcing output");
  wf->add_option("--module", o->module, "module number")->required();
  wf->add_option("--channel", o->channel, "output channel (0-based)")->required();
  wf->add_option("--fault", o->fault, "none, safe (wire reads low) or unsafe (wire reads high)")
      ->required();
  wf->callback([o] {
    request(*o, "POST", "/api/wiring_fault",
            {{"module", o->module}, {"channel", o->channel}, {"fault", o->fault}},
            print_fault_answer);
  });

  CLI::App* sensor = command(ctl, o, "sensor", "open/close a thermocouple or RTD, loop ohms");
  sensor->add_option("--module", o->module, "module number")->required();
  sensor->add_option("--channel", o->channel, "input channel (0-based)")->required();
  auto* open = sensor->add_flag("--open", o->open, "break the sensor wire");
  sensor->add_flag("--close", o->close, "repair it")->excludes(open);
  sensor->add_option("--loop-ohms", o->loop_ohms, "thermocouple loop resistance (0x5nn4)");
  sensor->callback([o] {
    json body{{"module", o->module}, {"channel", o->channel}};
    if (o->open || o->close) body["open"] = o->open;
    if (o->loop_ohms) body["loop_ohms"] = *o->loop_ohms;
    request(*o, "POST", "/api/sensor", body, print_module);
  });

  CLI::App* uart = command(ctl, o, "uart", "inject received bytes or line errors");
  uart->add_option("--module", o->module, "UART module number")->required();
  uart->add_option("--channel", o->channel, "channel 0..3")->required();
  uart->add_option("--text", o->text, "bytes as text");
  uart->add_option("--hex", o->hex, "bytes as hex, e.g. 0d0a");
  uart->add_option("--error", o->error, "overflow, framing, parity or tx_overflow");
  uart->add_option("--cts", o->cts, "CTS from the slot card: true or false");
  uart->callback([o] {
    json body{{"module", o->module}, {"channel", o->channel}};
    if (!o->text.empty()) body["text"] = o->text;
    if (!o->hex.empty()) body["hex"] = o->hex;
    if (!o->error.empty()) body["error"] = o->error;
    if (!o->cts.empty()) {
      if (o->cts != "true" && o->cts != "false") {
        std::fprintf(stderr, "rackcat ctl uart: --cts must be true or false\n");
        exit_with(2);
      }
      body["cts"] = o->cts == "true";
    }
    request(*o, "POST", "/api/uart/inject", body, print_uart);
  });
}

const CommandRegistrar reg{"ctl", add_ctl};

}  // namespace
}  // namespace rackcat::apps
