#include "modules/control/control_api.hpp"

#include <fmt/format.h>
#include <httplib.h>

#include <chrono>
#include <future>
#include <stdexcept>

#include "modules/cards/uart_driver.hpp"

namespace rackcat::modules {
namespace {

using json = nlohmann::json;

struct BadRequest : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

const char* esm_name(coe::EsmState s) {
  switch (s) {
    case coe::EsmState::Init:
      return "INIT";
    case coe::EsmState::PreOp:
      return "PREOP";
    case coe::EsmState::Boot:
      return "BOOT";
    case coe::EsmState::SafeOp:
      return "SAFEOP";
    case coe::EsmState::Op:
      return "OP";
  }
  return "?";
}

const char* rim_state_name(RimState s) {
  switch (s) {
    case RimState::Offline:
      return "offline";
    case RimState::Connected:
      return "connected";
    case RimState::Online:
      return "online";
    case RimState::Error:
      return "error";
  }
  return "?";
}

const char* fault_name(WiringFault f) {
  switch (f) {
    case WiringFault::None:
      return "none";
    case WiringFault::ShortToGround:
      return "safe";
    case WiringFault::ShortToSupply:
      return "unsafe";
  }
  return "?";
}

double finite_or_zero(double v) {
  return std::isfinite(v) ? v : 0.0;
}

// Text that echoes request bytes (paths, file contents in parse errors) may not be UTF-8; a
// JSON answer must be. Anything outside printable ASCII becomes '?'.
std::string printable(std::string_view s) {
  std::string out(s.substr(0, 512));
  for (char& c : out) {
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7F) c = '?';
  }
  return out;
}

// Typed field access with precise errors.
const json& field(const json& body, const char* key) {
  if (!body.is_object()) throw BadRequest("the request body must be a JSON object");
  auto it = body.find(key);
  if (it == body.end()) throw BadRequest(fmt::format("missing field '{}'", key));
  return *it;
}
int64_t integer(const json& body, const char* key, int64_t lo, int64_t hi) {
  const json& v = field(body, key);
  if (!v.is_number_integer()) throw BadRequest(fmt::format("'{}' must be an integer", key));
  const auto x = v.get<int64_t>();
  if (x < lo || x > hi) throw BadRequest(fmt::format("'{}' must be {}..{}", key, lo, hi));
  return x;
}
double number(const json& body, const char* key) {
  const json& v = field(body, key);
  if (!v.is_number()) throw BadRequest(fmt::format("'{}' must be a number", key));
  return v.get<double>();
}
bool boolean(const json& body, const char* key, bool fallback) {
  if (!body.contains(key)) return fallback;
  const json& v = body.at(key);
  if (!v.is_boolean()) throw BadRequest(fmt::format("'{}' must be true or false", key));
  return v.get<bool>();
}
std::string text(const json& body, const char* key) {
  const json& v = field(body, key);
  if (!v.is_string()) throw BadRequest(fmt::format("'{}' must be a string", key));
  return v.get<std::string>();
}

json module_json(Rack& rack, const CardDriver& d) {
  const mdp::Module& m = d.module();
  json j{{"module", m.number},
         {"rim", m.rim},
         {"slot", m.slot},
         {"card", std::string(m.card->name)},
         {"description", std::string(m.card->description)},
         {"card_id", fmt::format("0x{:04X}", m.card->card_id)},
         {"module_ident", fmt::format("0x{:08X}", m.card->module_ident)}};
  json inputs = json::array();
  for (size_t i = 0; i < d.inputs().size(); ++i) {
    const InputChannel& in = d.inputs()[i];
    json c{{"channel", i},
           {"value", finite_or_zero(in.value)},
           {"unit", d.input_unit()},
           {"code", in.code},
           {"source", in.source->describe()}};
    if (d.has_sensor_break()) c["open"] = in.open;
    if (d.card().thermocouple_ohms) c["loop_ohms"] = in.loop_ohms;
    inputs.push_back(std::move(c));
  }
  json outputs = json::array();
  for (size_t i = 0; i < d.outputs().size(); ++i) {
    const OutputChannel& o = d.outputs()[i];
    json c{{"channel", i},   {"commanded", o.commanded}, {"driven", o.driven},
           {"wire", o.wire}, {"code", o.code},           {"unit", d.output_unit()}};
    if (d.detects_wiring_faults()) c["wiring_fault"] = fault_name(o.fault);
    outputs.push_back(std::move(c));
  }
  j["inputs"] = std::move(inputs);
  j["outputs"] = std::move(outputs);
  if (const auto* u = dynamic_cast<const UartDriver*>(&d)) {
    json ch = json::array();
    for (size_t c = 0; c < 4; ++c) {
      const UartDriver::Channel& uc = u->channel(c);
      ch.push_back({{"channel", c},
                    {"pty", uc.path},
                    {"baud", uc.config.baud_rate()},
                    {"parity", uc.config.parity == 0   ? "none"
                               : uc.config.parity == 1 ? "even"
                                                       : "odd"},
                    {"data_bits", 5 + std::min<int>(uc.config.data_bits, 3)},
                    {"stop_bits", uc.config.stop_bits ? 2 : 1},
                    {"flow", uc.config.flow == 0   ? "none"
                             : uc.config.flow == 1 ? "xon/xoff"
                                                   : "rts/cts"},
                    {"status", fmt::format("0x{:04X}", u->status_word(c))},
                    {"rx_available", uc.rx.size()},
                    {"tx_pending", uc.tx.size()},
                    {"errors", fmt::format("0x{:02X}", uc.errors.load())},
                    {"cts", uc.cts.load()},
                    {"hold", uc.hold.load()}});
    }
    j["uart"] = std::move(ch);
  }
  (void)rack;
  return j;
}

json exceptions_json(Rack& rack) {
  const ExceptionTree& t = rack.exceptions();
  auto hex32 = [](uint32_t v) { return fmt::format("0x{:08X}", v); };
  json rims = json::array();
  for (const auto& [rr, rim] : rack.rims()) {
    rims.push_back({{"rim", rr},
                    {"state", rim_state_name(rim.state)},
                    {"event_status", hex32(t.rim_event_status(rr))}});
  }
  json modules = json::array();
  for (const auto& d : rack.drivers()) {
    const uint16_t n = d->module().number;
    const uint32_t w = t.module_warnings(n, false), e = t.module_errors(n, false);
    const uint32_t wl = t.module_warnings(n, true), el = t.module_errors(n, true);
    if (w | e | wl | el) {
      modules.push_back({{"module", n},
                         {"F382", hex32(w)},
                         {"F384", hex32(e)},
                         {"F392", hex32(wl)},
                         {"F394", hex32(el)}});
    }
  }
  return {{"F380", hex32(t.summary(false))},
          {"F390", hex32(t.summary(true))},
          {"F386", hex32(t.global_warnings(false))},
          {"F388", hex32(t.global_errors(false))},
          {"F396", hex32(t.global_warnings(true))},
          {"F398", hex32(t.global_errors(true))},
          {"device_event_status", hex32(t.device_event_status())},
          {"rims", std::move(rims)},
          {"modules", std::move(modules)}};
}

json rack_json(Rack& rack) {
  json rims = json::array();
  for (const auto& [rr, rim] : rack.rims()) {
    rims.push_back({{"rim", rr},
                    {"state", rim_state_name(rim.state)},
                    {"comm_error", rim.comm_error},
                    {"power_supply_fan", rim.power_supply_fan},
                    {"power_supply_rpm", rim.power_supply_rpm},
                    {"slot_card_fan", rim.slot_card_fan},
                    {"slot_card_rpm", rim.slot_card_rpm},
                    {"modules", rim.modules}});
  }
  json modules = json::array();
  for (const auto& d : rack.drivers()) modules.push_back(module_json(rack, *d));
  return {{"esm", esm_name(rack.esm_state())},
          {"outputs_valid", rack.outputs_valid()},
          {"detect_modules_override", rack.detect_modules_override()},
          {"cpu_fan_rpm", rack.cpu_fan_rpm()},
          {"cpu_temperature", rack.cpu_temperature()},
          {"cpu_temperature_published", rack.cpu_temperature_published()},
          {"rims", std::move(rims)},
          {"modules", std::move(modules)}};
}

std::string param_string(const json& v) {
  if (v.is_string()) return v.get<std::string>();
  if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
  if (v.is_number_integer()) return std::to_string(v.get<int64_t>());
  if (v.is_number()) return fmt::format("{}", v.get<double>());
  throw BadRequest("source parameters must be strings, numbers or booleans");
}

std::vector<uint8_t> parse_hex(const std::string& s) {
  std::vector<uint8_t> out;
  int nibble = -1;
  for (char c : s) {
    int v;
    if (c >= '0' && c <= '9')
      v = c - '0';
    else if (c >= 'a' && c <= 'f')
      v = c - 'a' + 10;
    else if (c >= 'A' && c <= 'F')
      v = c - 'A' + 10;
    else if (c == ' ' || c == ':')
      continue;
    else
      throw BadRequest(fmt::format("'hex' has a non-hex character '{}'", c));
    if (nibble < 0) {
      nibble = v;
    } else {
      out.push_back(static_cast<uint8_t>(nibble << 4 | v));
      nibble = -1;
    }
  }
  if (nibble >= 0) throw BadRequest("'hex' has an odd number of digits");
  return out;
}

}  // namespace

ControlApi::ControlApi(Rack& rack, PostFn post)
    : rack_(rack), post_(std::move(post)), alive_(std::make_shared<std::atomic<bool>>(true)) {}

ControlApi::~ControlApi() {
  stop();
}

ControlApi::Response ControlApi::handle(std::string_view method, std::string_view path,
                                        std::string_view body) {
  json parsed = json::object();
  if (!body.empty()) {
    parsed = json::parse(body, nullptr, false);
    if (parsed.is_discarded()) return {400, {{"error", "the request body is not valid JSON"}}};
  }
  try {
    return dispatch(method, path, parsed);
  } catch (const std::invalid_argument& e) {
    return {400, {{"error", printable(e.what())}}};
  } catch (const std::exception& e) {
    return {500, {{"error", printable(e.what())}}};
  }
}

ControlApi::Response ControlApi::dispatch(std::string_view method, std::string_view path,
                                          const json& body) {
  const bool get = method == "GET";
  const bool post = method == "POST";
  auto wrong_method = [&] {
    return Response{
        405, {{"error", fmt::format("{} does not accept {}", printable(path), printable(method))}}};
  };

  if (path == "/api/rack") {
    if (!get) return wrong_method();
    rack_.refresh();
    return {200, rack_json(rack_)};
  }
  if (path.starts_with("/api/modules/")) {
    if (!get) return wrong_method();
    const std::string_view num = path.substr(std::string_view("/api/modules/").size());
    int n = 0;
    for (char c : num) {
      if (c < '0' || c > '9' || n > 1000) throw BadRequest("module number must be 1..255");
      n = n * 10 + (c - '0');
    }
    CardDriver* d = rack_.driver(static_cast<uint16_t>(n));
    if (num.empty() || d == nullptr)
      return {404, {{"error", fmt::format("there is no module {}", printable(num))}}};
    rack_.refresh();
    return {200, module_json(rack_, *d)};
  }
  if (path == "/api/esm") {
    if (!get) return wrong_method();
    return {200,
            {{"state", esm_name(rack_.esm_state())},
             {"outputs_valid", rack_.outputs_valid()},
             {"detect_modules_override", rack_.detect_modules_override()}}};
  }
  if (path == "/api/exceptions") {
    if (!get) return wrong_method();
    rack_.refresh();
    return {200, exceptions_json(rack_)};
  }
  if (path == "/api/channel") {
    if (!post) return wrong_method();
    const auto module = static_cast<uint16_t>(integer(body, "module", 1, 255));
    const auto channel = static_cast<size_t>(integer(body, "channel", 0, 31));
    std::string kind;
    SourceParams params;
    if (body.contains("value")) {
      kind = "constant";
      params["value"] = param_string(field(body, "value"));
      if (body.contains("source")) throw BadRequest("give either 'value' or 'source', not both");
    } else {
      kind = text(body, "source");
      if (body.contains("params")) {
        const json& p = body.at("params");
        if (!p.is_object()) throw BadRequest("'params' must be an object");
        for (auto it = p.begin(); it != p.end(); ++it) params[it.key()] = param_string(it.value());
      }
    }
    rack_.set_source(module, channel, kind, params);
    rack_.refresh();
    return {200, module_json(rack_, *rack_.driver(module))};
  }
  if (path == "/api/rim/unplug" || path == "/api/rim/replug" || path == "/api/rim/state") {
    if (!post) return wrong_method();
    const auto rr = static_cast<uint8_t>(integer(body, "rim", 1, 5));
    if (!rack_.rims().count(rr)) throw BadRequest(fmt::format("there is no RIM {}", rr));
    if (path == "/api/rim/unplug") {
      rack_.set_rim_state(rr, RimState::Offline, boolean(body, "comm_error", false));
    } else if (path == "/api/rim/replug") {
      rack_.set_rim_state(rr, RimState::Online, false);
    } else {
      const std::string s = text(body, "state");
      RimState st;
      if (s == "offline")
        st = RimState::Offline;
      else if (s == "connected")
        st = RimState::Connected;
      else if (s == "online")
        st = RimState::Online;
      else if (s == "error")
        st = RimState::Error;
      else
        throw BadRequest("'state' must be offline, connected, online or error");
      rack_.set_rim_state(rr, st, boolean(body, "comm_error", false));
    }
    rack_.refresh();
    return {200, exceptions_json(rack_)};
  }
  if (path == "/api/rim/mcm") {
    if (!post) return wrong_method();
    const auto rr = static_cast<uint8_t>(integer(body, "rim", 1, 5));
    if (!rack_.rims().count(rr)) throw BadRequest(fmt::format("there is no RIM {}", rr));
    const json& list = field(body, "errors");
    if (!list.is_array()) throw BadRequest("'errors' must be an array (possibly empty)");
    uint32_t bits = 0;
    for (const json& e : list) {
      const std::string name = e.is_string() ? e.get<std::string>() : std::string();
      if (name == "slot_machine_mcm0")
        bits |= rim_event::kSlotMachineMcm0;
      else if (name == "sout_compare_mcm0")
        bits |= rim_event::kSoutCompareMcm0;
      else if (name == "slot_machine_mcm1")
        bits |= rim_event::kSlotMachineMcm1;
      else if (name == "sout_compare_mcm1")
        bits |= rim_event::kSoutCompareMcm1;
      else
        throw BadRequest(
            "'errors' entries are slot_machine_mcm0, sout_compare_mcm0, slot_machine_mcm1, "
            "sout_compare_mcm1");
    }
    rack_.set_rim_mcm_errors(rr, bits);
    rack_.refresh();
    return {200, exceptions_json(rack_)};
  }
  if (path == "/api/fan") {
    if (!post) return wrong_method();
    const auto rr = static_cast<uint8_t>(integer(body, "rim", 0, 5));
    const std::string zone = body.contains("zone") ? text(body, "zone") : std::string();
    rack_.set_fan_rpm(rr, zone, number(body, "rpm"));
    rack_.refresh();
    return {200, exceptions_json(rack_)};
  }
  if (path == "/api/cpu_temperature") {
    if (!post) return wrong_method();
    rack_.set_cpu_temperature(number(body, "celsius"), boolean(body, "immediate", false));
    return {200,
            {{"cpu_temperature", rack_.cpu_temperature()},
             {"published", rack_.cpu_temperature_published()}}};
  }
  if (path == "/api/wiring_fault") {
    if (!post) return wrong_method();
    const auto module = static_cast<uint16_t>(integer(body, "module", 1, 255));
    const auto channel = static_cast<size_t>(integer(body, "channel", 0, 31));
    const std::string f = text(body, "fault");
    WiringFault fault;
    if (f == "none")
      fault = WiringFault::None;
    else if (f == "safe" || f == "short_to_ground")
      fault = WiringFault::ShortToGround;
    else if (f == "unsafe" || f == "short_to_supply")
      fault = WiringFault::ShortToSupply;
    else
      throw BadRequest("'fault' must be none, safe (short_to_ground) or unsafe (short_to_supply)");
    rack_.set_wiring_fault(module, channel, fault);
    rack_.refresh();
    return {200, exceptions_json(rack_)};
  }
  if (path == "/api/sensor") {
    if (!post) return wrong_method();
    const auto module = static_cast<uint16_t>(integer(body, "module", 1, 255));
    const auto channel = static_cast<size_t>(integer(body, "channel", 0, 31));
    if (!body.contains("open") && !body.contains("loop_ohms"))
      throw BadRequest("give 'open' and/or 'loop_ohms'");
    if (body.contains("loop_ohms")) rack_.set_loop_ohms(module, channel, number(body, "loop_ohms"));
    if (body.contains("open")) rack_.set_sensor_open(module, channel, boolean(body, "open", false));
    rack_.refresh();
    return {200, module_json(rack_, *rack_.driver(module))};
  }
  if (path == "/api/uart/inject") {
    if (!post) return wrong_method();
    const auto module = static_cast<uint16_t>(integer(body, "module", 1, 255));
    const auto channel = static_cast<size_t>(integer(body, "channel", 0, 3));
    auto* u = dynamic_cast<UartDriver*>(rack_.driver(module));
    if (u == nullptr) throw BadRequest(fmt::format("module {} is not a UART card", module));
    std::vector<uint8_t> bytes;
    if (body.contains("text")) {
      const std::string t = text(body, "text");
      bytes.assign(t.begin(), t.end());
    }
    if (body.contains("hex")) {
      const auto h = parse_hex(text(body, "hex"));
      bytes.insert(bytes.end(), h.begin(), h.end());
    }
    uint8_t error_bits = 0;
    if (body.contains("error")) {
      const std::string e = text(body, "error");
      if (e == "overflow")
        error_bits = uart::kErrRxOverflow;
      else if (e == "framing")
        error_bits = uart::kErrFraming;
      else if (e == "parity")
        error_bits = uart::kErrParity;
      else if (e == "tx_overflow")
        error_bits = uart::kErrTxOverflow;
      else
        throw BadRequest("'error' must be overflow, framing, parity or tx_overflow");
    }
    const bool has_cts = body.contains("cts");
    const bool cts = boolean(body, "cts", true);
    if (bytes.empty() && error_bits == 0 && !has_cts)
      throw BadRequest("give 'text', 'hex', 'error' and/or 'cts'");
    const size_t accepted = u->inject_rx(channel, bytes.data(), bytes.size());
    if (error_bits) u->inject_error(channel, error_bits);
    if (has_cts) u->channel(channel).cts = cts;
    rack_.refresh();
    json j = module_json(rack_, *u);
    j["accepted"] = accepted;
    return {200, j};
  }
  return {404, {{"error", fmt::format("no endpoint {} {}", printable(method), printable(path))}}};
}

uint16_t ControlApi::listen(uint16_t port) {
  server_ = std::make_unique<httplib::Server>();
  auto serve = [this](const httplib::Request& req, httplib::Response& res) {
    auto promise = std::make_shared<std::promise<Response>>();
    auto future = promise->get_future();
    auto alive = alive_;
    const std::string method = req.method, path = req.path, body = req.body;
    auto task = [this, promise, alive, method, path, body] {
      if (!alive->load()) return;
      promise->set_value(handle(method, path, body));
    };
    if (post_) {
      post_(task);
    } else {
      task();
    }
    Response r;
    if (future.wait_for(std::chrono::seconds(2)) == std::future_status::ready) {
      r = future.get();
    } else {
      r = {503, {{"error", "the device thread did not answer within 2 s"}}};
    }
    res.status = r.status;
    res.set_content(r.body.dump(2) + "\n", "application/json");
  };
  server_->Get(R"(/.*)", serve);
  server_->Post(R"(/.*)", serve);
  int bound = 0;
  if (port == 0) {
    bound = server_->bind_to_any_port("127.0.0.1");
  } else {
    bound = server_->bind_to_port("127.0.0.1", port) ? port : -1;
  }
  if (bound <= 0) {
    server_.reset();
    throw std::runtime_error(fmt::format("control API: cannot listen on 127.0.0.1:{}", port));
  }
  thread_ = std::thread([this] { server_->listen_after_bind(); });
  return static_cast<uint16_t>(bound);
}

void ControlApi::stop() {
  alive_->store(false);
  if (server_) server_->stop();
  if (thread_.joinable()) thread_.join();
  server_.reset();
}

}  // namespace rackcat::modules
